// The SPSC ring and the newest-slot: single-thread semantics, then threaded stress tests (millions
// of items, order and count kept) that also run under ThreadSanitizer (tools/tsan-runtime).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "stairguide/runtime/spsc_ring.hpp"

using stairguide::runtime::NewestSlot;
using stairguide::runtime::ring_capacity_for;
using stairguide::runtime::SpscRing;

namespace {

#if defined(__SANITIZE_THREAD__)
constexpr std::uint64_t kStressItems = 2'000'000;  // TSan is ~10x slower: two million
#else
constexpr std::uint64_t kStressItems = 10'000'000;
#endif

}  // namespace

TEST(SpscRing, CapacityIsRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(ring_capacity_for(0), 2u);
  EXPECT_EQ(ring_capacity_for(2), 2u);
  EXPECT_EQ(ring_capacity_for(3), 4u);
  EXPECT_EQ(ring_capacity_for(8), 8u);
  EXPECT_EQ(ring_capacity_for(9), 16u);
  SpscRing<int> r(5);
  EXPECT_EQ(r.capacity(), 8u);
}

TEST(SpscRing, FifoOrderAndFullEmpty) {
  SpscRing<int> r(4);
  int out = -1;
  EXPECT_FALSE(r.try_pop(out));
  EXPECT_TRUE(r.empty());
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(r.try_push(i)) << i;
  EXPECT_TRUE(r.full());
  int extra = 99;
  EXPECT_FALSE(r.try_push(extra));
  EXPECT_EQ(extra, 99) << "a refused element must be left untouched";
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(r.try_pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(r.try_pop(out));
  // Wrap around many times.
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(r.try_push(i));
    ASSERT_TRUE(r.try_push(i + 1));
    ASSERT_TRUE(r.try_pop(out));
    EXPECT_EQ(out, i);
    ASSERT_TRUE(r.try_pop(out));
    EXPECT_EQ(out, i + 1);
  }
  EXPECT_EQ(r.pushed(), 2004u);
}

TEST(SpscRing, MoveOnlyElementsAndResourcesReleased) {
  SpscRing<std::unique_ptr<int>> r(2);
  auto a = std::make_unique<int>(7);
  ASSERT_TRUE(r.try_push(a));
  EXPECT_EQ(a, nullptr);
  std::unique_ptr<int> b = std::make_unique<int>(8);
  ASSERT_TRUE(r.try_push(std::move(b)));
  auto c = std::make_unique<int>(9);
  EXPECT_FALSE(r.try_push(c));
  ASSERT_NE(c, nullptr) << "refused element was moved from";
  std::unique_ptr<int> out;
  ASSERT_TRUE(r.try_pop(out));
  EXPECT_EQ(*out, 7);

  // A shared_ptr held by a skipped slot is released when pop_newest discards it.
  SpscRing<std::shared_ptr<int>> s(4);
  auto p = std::make_shared<int>(1);
  std::weak_ptr<int> wp = p;
  ASSERT_TRUE(s.try_push(std::move(p)));
  ASSERT_TRUE(s.try_push(std::make_shared<int>(2)));
  std::shared_ptr<int> newest;
  EXPECT_EQ(s.pop_newest(newest), 1);
  EXPECT_EQ(*newest, 2);
  EXPECT_TRUE(wp.expired()) << "the skipped element was kept alive in its slot";
}

TEST(SpscRing, PushOrDropCountsDrops) {
  SpscRing<int> r(2);
  EXPECT_TRUE(r.push_or_drop(1));
  EXPECT_TRUE(r.push_or_drop(2));
  EXPECT_FALSE(r.push_or_drop(3));
  EXPECT_FALSE(r.push_or_drop(4));
  EXPECT_EQ(r.dropped(), 2u);
  int out = 0;
  ASSERT_TRUE(r.try_pop(out));
  EXPECT_EQ(out, 1);
  EXPECT_TRUE(r.push_or_drop(5));
  EXPECT_EQ(r.dropped(), 2u);
}

TEST(SpscRing, PopNewestSkipsAndCounts) {
  SpscRing<int> r(8);
  int out = -1;
  EXPECT_EQ(r.pop_newest(out), -1);
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(r.try_push(i));
  EXPECT_EQ(r.pop_newest(out), 4);
  EXPECT_EQ(out, 4);
  EXPECT_TRUE(r.empty());
  EXPECT_EQ(r.skipped(), 4u);
  ASSERT_TRUE(r.try_push(10));
  EXPECT_EQ(r.pop_newest(out), 0);
  EXPECT_EQ(out, 10);
  EXPECT_EQ(r.skipped(), 4u);
  // After a skip, all slots are free again.
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(r.try_push(i));
}

TEST(NewestSlot, OverwritesAndCounts) {
  NewestSlot<std::unique_ptr<int>> s;
  std::unique_ptr<int> out;
  EXPECT_FALSE(s.take(out));
  EXPECT_TRUE(s.publish(std::make_unique<int>(1)));
  EXPECT_TRUE(s.has_new());
  ASSERT_TRUE(s.take(out));
  EXPECT_EQ(*out, 1);
  EXPECT_FALSE(s.take(out));
  EXPECT_TRUE(s.publish(std::make_unique<int>(2)));
  EXPECT_FALSE(s.publish(std::make_unique<int>(3)));
  EXPECT_FALSE(s.publish(std::make_unique<int>(4)));
  ASSERT_TRUE(s.take(out));
  EXPECT_EQ(*out, 4);
  EXPECT_EQ(s.overwritten(), 2u);
  EXPECT_EQ(s.published(), 4u);
  EXPECT_EQ(s.taken(), 2u);
  EXPECT_EQ(s.published(), s.taken() + s.overwritten());
}

// Producer and consumer on their own threads; every item arrives once, in order.
TEST(SpscRingStress, MillionsOfItemsKeepOrderAndCount) {
  SpscRing<std::uint64_t> r(64);
  std::atomic<bool> go{false};
  std::thread producer([&] {
    while (!go.load(std::memory_order_acquire)) std::this_thread::yield();
    for (std::uint64_t i = 0; i < kStressItems; ++i) {
      std::uint64_t v = i;
      while (!r.try_push(v)) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0, out_of_order = 0, sum = 0;
  go.store(true, std::memory_order_release);
  while (expected < kStressItems) {
    std::uint64_t v = 0;
    if (!r.try_pop(v)) {
      std::this_thread::yield();
      continue;
    }
    if (v != expected) ++out_of_order;
    sum += v;
    ++expected;
  }
  producer.join();
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(sum, kStressItems * (kStressItems - 1) / 2);
  EXPECT_TRUE(r.empty());
  EXPECT_EQ(r.pushed(), kStressItems);
}

// Heap-owning move-only payloads: checks the consumer sees the producer's writes to the pointee.
TEST(SpscRingStress, MoveOnlyPayloadsArriveIntact) {
  constexpr std::uint64_t n = kStressItems / 8;
  SpscRing<std::unique_ptr<std::vector<std::uint64_t>>> r(16);
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < n; ++i) {
      auto p = std::make_unique<std::vector<std::uint64_t>>(4, i);
      while (!r.try_push(p)) std::this_thread::yield();
    }
  });
  std::uint64_t got = 0, bad = 0;
  while (got < n) {
    std::unique_ptr<std::vector<std::uint64_t>> p;
    if (!r.try_pop(p)) {
      std::this_thread::yield();
      continue;
    }
    for (auto v : *p) bad += (v != got);
    ++got;
  }
  producer.join();
  EXPECT_EQ(bad, 0u);
}

namespace {

// What a consumer received from a producer that sets `done` when it has sent everything.
struct Received {
  std::uint64_t items = 0, regressions = 0;  // regressions: values not above the one received before
  std::uint64_t last = 0;                    // the last value received
};

// Takes with `take(value)` (false: nothing there) until the producer is done and nothing is left.
template <class Take>
Received receive_until_done(const std::atomic<bool>& done, Take take) {
  Received got;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    std::uint64_t v = 0;
    if (take(v)) {
      if (got.items > 0 && v <= got.last) ++got.regressions;
      got.last = v;
      ++got.items;
    } else if (finished) {
      break;
    } else {
      std::this_thread::yield();
    }
  }
  return got;
}

}  // namespace

// Skip-to-newest and drop-when-full under contention: values only increase, and
// received + skipped + dropped == produced.
TEST(SpscRingStress, PopNewestAndDropsAccountForEveryItem) {
  SpscRing<std::uint64_t> r(8);
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kStressItems; ++i) r.push_or_drop(std::uint64_t{i});
    done.store(true, std::memory_order_release);
  });
  const Received got = receive_until_done(done, [&](std::uint64_t& v) { return r.pop_newest(v) >= 0; });
  producer.join();
  const std::uint64_t received = got.items, regressions = got.regressions;
  EXPECT_EQ(regressions, 0u);
  EXPECT_EQ(received + r.skipped() + r.dropped(), kStressItems);
  EXPECT_GT(received, 0u);
}

TEST(NewestSlotStress, ConsumerSeesIncreasingValuesAndEveryItemIsAccounted) {
  NewestSlot<std::unique_ptr<std::uint64_t>> s;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kStressItems; ++i) s.publish(std::make_unique<std::uint64_t>(i));
    done.store(true, std::memory_order_release);
  });
  const Received got = receive_until_done(done, [&](std::uint64_t& v) {
    std::unique_ptr<std::uint64_t> p;
    if (!s.take(p)) return false;
    v = *p;
    return true;
  });
  producer.join();
  const std::uint64_t received = got.items, regressions = got.regressions;
  EXPECT_EQ(regressions, 0u);
  EXPECT_EQ(received, s.taken());
  EXPECT_EQ(s.taken() + s.overwritten(), kStressItems);
  EXPECT_EQ(got.last, kStressItems - 1);
}
