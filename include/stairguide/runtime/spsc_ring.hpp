#pragma once
/// \file spsc_ring.hpp
/// Bounded single-producer/single-consumer lock-free queues joining the daemon's threads.
///
/// - `SpscRing<T>`: a FIFO ring of power-of-two capacity. `try_push` fails when full (the caller
///   decides to wait or to drop, and counts it); `try_pop` takes the oldest; `pop_newest` is the
///   skip-to-newest policy: it takes the newest element and discards the older ones, returning how
///   many it skipped so the caller counts them.
/// - `NewestSlot<T>`: the overwrite policy (a lock-free triple buffer, in effect a ring of one that
///   overwrites): the producer always publishes, replacing an element the consumer has not taken;
///   every replaced element is counted in `overwritten()`. Perception reads its frames here so it
///   always works on the present and never on a backlog.
///
/// Exactly one thread may call the producer methods and exactly one (other) thread the consumer
/// methods. The statistics getters may be called from any thread. Elements only need to be default
/// constructible and move-assignable (move-only types such as `std::unique_ptr` are fine); a slot
/// keeps the moved-from value until it is reused.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace stairguide::runtime {

/// Size used to keep the producer's and the consumer's hot data on separate cache lines.
inline constexpr std::size_t kCacheLine = 64;

/// Smallest power of two >= n (and >= 2).
constexpr std::size_t ring_capacity_for(std::size_t n) {
  std::size_t c = 2;
  while (c < n) c <<= 1;
  return c;
}

/// Bounded SPSC FIFO ring. Indices grow without wrapping (64-bit); slot = index & mask.
template <class T>
class SpscRing {
  static_assert(std::is_default_constructible_v<T>, "SpscRing<T>: T must be default constructible");
  static_assert(std::is_move_assignable_v<T>, "SpscRing<T>: T must be move assignable");

 public:
  /// `capacity` is rounded up to a power of two (at least 2).
  explicit SpscRing(std::size_t capacity)
      : capacity_(ring_capacity_for(capacity)), mask_(capacity_ - 1), slots_(new Slot[capacity_]) {}

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const { return capacity_; }

  // ---- producer ----

  /// Moves `value` in and returns true; returns false and leaves `value` untouched when full.
  bool try_push(T& value) {
    const std::uint64_t tail = tail_.value.load(std::memory_order_relaxed);
    if (tail - head_cache_.value >= capacity_) {
      head_cache_.value = head_.value.load(std::memory_order_acquire);
      if (tail - head_cache_.value >= capacity_) return false;
    }
    slots_[tail & mask_].value = std::move(value);
    tail_.value.store(tail + 1, std::memory_order_release);
    return true;
  }
  bool try_push(T&& value) { return try_push(value); }

  /// Pushes, or when full counts the element in `dropped()` and returns false (the element is
  /// discarded by the caller). For producers that must never wait (a live camera).
  bool push_or_drop(T&& value) {
    if (try_push(value)) return true;
    dropped_.value.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  // ---- consumer ----

  /// Moves the oldest element into `out`; false when empty.
  bool try_pop(T& out) {
    const std::uint64_t head = head_.value.load(std::memory_order_relaxed);
    if (head == tail_cache_.value) {
      tail_cache_.value = tail_.value.load(std::memory_order_acquire);
      if (head == tail_cache_.value) return false;
    }
    out = std::move(slots_[head & mask_].value);
    head_.value.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Skip-to-newest: moves the newest element into `out`, discards every older one (their slots
  /// are released to the producer) and adds their number to `skipped()`. Returns the number
  /// skipped, or -1 when the ring was empty.
  long pop_newest(T& out) {
    const std::uint64_t head = head_.value.load(std::memory_order_relaxed);
    tail_cache_.value = tail_.value.load(std::memory_order_acquire);
    const std::uint64_t tail = tail_cache_.value;
    if (head == tail) return -1;
    for (std::uint64_t i = head; i + 1 < tail; ++i) slots_[i & mask_].value = T();  // release resources
    out = std::move(slots_[(tail - 1) & mask_].value);
    head_.value.store(tail, std::memory_order_release);
    const auto n = static_cast<long>(tail - 1 - head);
    skipped_.value.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
    return n;
  }

  // ---- either side / observers ----

  /// Elements in the ring (exact from the producer or consumer, approximate elsewhere).
  std::size_t size() const {
    const std::uint64_t head = head_.value.load(std::memory_order_acquire);
    const std::uint64_t tail = tail_.value.load(std::memory_order_acquire);
    return tail >= head ? static_cast<std::size_t>(tail - head) : 0;
  }
  bool empty() const { return size() == 0; }
  bool full() const { return size() >= capacity_; }

  /// Elements pushed so far.
  std::uint64_t pushed() const { return tail_.value.load(std::memory_order_acquire); }
  /// Elements refused by `push_or_drop` because the ring was full.
  std::uint64_t dropped() const { return dropped_.value.load(std::memory_order_relaxed); }
  /// Elements discarded by `pop_newest`.
  std::uint64_t skipped() const { return skipped_.value.load(std::memory_order_relaxed); }

 private:
  template <class V>
  struct alignas(kCacheLine) Padded {
    V value{};
  };
  struct alignas(kCacheLine) Slot {
    T value{};
  };

  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<Slot[]> slots_;
  // Consumer-owned: its index and its cached copy of the producer's.
  Padded<std::atomic<std::uint64_t>> head_;
  Padded<std::uint64_t> tail_cache_;
  Padded<std::atomic<std::uint64_t>> skipped_;
  // Producer-owned.
  Padded<std::atomic<std::uint64_t>> tail_;
  Padded<std::uint64_t> head_cache_;
  Padded<std::atomic<std::uint64_t>> dropped_;
};

/// Overwrite-to-newest SPSC slot (triple buffer). The producer never waits and never fails; the
/// consumer always gets the latest published element. Elements replaced before the consumer took
/// them are counted, never silently lost.
template <class T>
class NewestSlot {
  static_assert(std::is_default_constructible_v<T>, "NewestSlot<T>: T must be default constructible");
  static_assert(std::is_move_assignable_v<T>, "NewestSlot<T>: T must be move assignable");

 public:
  NewestSlot() = default;
  NewestSlot(const NewestSlot&) = delete;
  NewestSlot& operator=(const NewestSlot&) = delete;

  /// Producer: publishes `value`. Returns false when it replaced an element the consumer had not
  /// taken (that element is counted in `overwritten()` and destroyed on the next publish).
  bool publish(T&& value) {
    slots_[back_].value = std::move(value);
    // Hand the back buffer over as the middle one; take the old middle as the next back buffer.
    const unsigned prev =
        middle_.value.exchange(static_cast<unsigned>(back_) | kFresh, std::memory_order_acq_rel);
    back_ = prev & kIndex;
    published_.value.fetch_add(1, std::memory_order_relaxed);
    if (prev & kFresh) {
      overwritten_.value.fetch_add(1, std::memory_order_relaxed);
      slots_[back_].value = T();  // free the replaced element now rather than at the next publish
      return false;
    }
    return true;
  }

  /// Consumer: moves the newest unread element into `out`; false when nothing new was published.
  bool take(T& out) {
    if (!(middle_.value.load(std::memory_order_relaxed) & kFresh)) return false;
    const unsigned prev = middle_.value.exchange(static_cast<unsigned>(front_), std::memory_order_acq_rel);
    front_ = prev & kIndex;
    out = std::move(slots_[front_].value);
    taken_.value.fetch_add(1, std::memory_order_relaxed);
    return true;
  }

  /// True when an unread element is waiting (any thread; a hint).
  bool has_new() const { return (middle_.value.load(std::memory_order_acquire) & kFresh) != 0; }

  std::uint64_t published() const { return published_.value.load(std::memory_order_relaxed); }
  std::uint64_t taken() const { return taken_.value.load(std::memory_order_relaxed); }
  /// Elements replaced before the consumer took them.
  std::uint64_t overwritten() const { return overwritten_.value.load(std::memory_order_relaxed); }

 private:
  static constexpr unsigned kFresh = 4u;
  static constexpr unsigned kIndex = 3u;
  template <class V>
  struct alignas(kCacheLine) Padded {
    V value{};
  };
  struct alignas(kCacheLine) Slot {
    T value{};
  };

  Slot slots_[3];
  Padded<std::atomic<unsigned>> middle_{1u};  // index of the middle buffer | kFresh when unread
  alignas(kCacheLine) unsigned back_ = 0;     // producer-owned
  Padded<std::atomic<std::uint64_t>> published_;
  Padded<std::atomic<std::uint64_t>> overwritten_;
  alignas(kCacheLine) unsigned front_ = 2;  // consumer-owned
  Padded<std::atomic<std::uint64_t>> taken_;
};

}  // namespace stairguide::runtime
