// A main for the libFuzzer harnesses of tests/fuzz without libFuzzer: built with gcc under
// ASan + UBSan (tools/sanitize, part of tools/check) it runs a harness on every file of its seed
// corpus, then on deterministic mutations of them (bit flips, random bytes, cut and repeated
// ranges, inserted tokens that readers choke on: NaN, huge numbers, NULs, YAML punctuation) for a
// bounded time. It is not coverage-guided (tools/fuzz is, with clang, for the long runs); it is the
// short bounded run CI can afford on every commit, reusing the ASan build of the readers.
//
// Usage: fuzzreplay_X CORPUS_DIR [SECONDS] [SEED]
//   Exits 0 after the time is up; a crash, a sanitizer report, a leak or an exception other than
//   the reader's own error (the harness lets it escape) ends it non-zero, with the input that did
//   it written to ./replay-crash-X (its path printed first).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#if __has_include(<sanitizer/common_interface_defs.h>)
#include <sanitizer/common_interface_defs.h>
#define SG_HAVE_SANITIZER_CALLBACK 1
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Rng {
  std::uint64_t s;
  std::uint64_t next() {  // xorshift64*
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 2685821657736338717ULL;
  }
  std::size_t below(std::size_t n) { return n ? static_cast<std::size_t>(next() % n) : 0; }
};

const char* const kTokens[] = {"\0",
                               "\xff",
                               "-1",
                               "0",
                               "1e300",
                               "-1e300",
                               "nan",
                               "inf",
                               ":",
                               "\n",
                               " ",
                               "[",
                               "]",
                               "{",
                               "}",
                               ",",
                               "- ",
                               "&a",
                               "*a",
                               "!!str ",
                               "---\n",
                               "...",
                               "\"",
                               "'",
                               "4294967296",
                               "18446744073709551615",
                               "SIZE ",
                               "COUNT ",
                               "DATA binary_compressed\n"};

Bytes mutate(Bytes b, Rng& r, const std::vector<Bytes>& corpus) {
  const int ops = 1 + static_cast<int>(r.below(4));
  for (int k = 0; k < ops; ++k) {
    switch (r.below(7)) {
      case 0:  // flip a bit
        if (!b.empty()) b[r.below(b.size())] ^= static_cast<std::uint8_t>(1u << r.below(8));
        break;
      case 1:  // a random byte
        if (!b.empty()) b[r.below(b.size())] = static_cast<std::uint8_t>(r.next());
        break;
      case 2: {  // cut a range
        if (b.empty()) break;
        const std::size_t at = r.below(b.size()), n = 1 + r.below(std::min<std::size_t>(b.size() - at, 64));
        b.erase(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n));
        break;
      }
      case 3: {  // repeat a range
        if (b.empty() || b.size() > (1u << 20)) break;
        const std::size_t at = r.below(b.size()), n = 1 + r.below(std::min<std::size_t>(b.size() - at, 64));
        const Bytes piece(b.begin() + static_cast<std::ptrdiff_t>(at),
                          b.begin() + static_cast<std::ptrdiff_t>(at + n));
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(r.below(b.size() + 1)), piece.begin(), piece.end());
        break;
      }
      case 4: {  // insert a token
        const std::string t = kTokens[r.below(std::size(kTokens))];
        const std::size_t len = t.empty() ? 1 : t.size();  // "\0" is one NUL byte
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(r.below(b.size() + 1)), t.data(), t.data() + len);
        break;
      }
      case 5:  // truncate
        b.resize(r.below(b.size() + 1));
        break;
      case 6: {  // splice with another seed
        const Bytes& o = corpus[r.below(corpus.size())];
        if (o.empty()) break;
        const std::size_t keep = r.below(b.size() + 1), from = r.below(o.size());
        b.resize(keep);
        b.insert(b.end(), o.begin() + static_cast<std::ptrdiff_t>(from), o.end());
        break;
      }
    }
  }
  return b;
}

// Plain storage that outlives the static destructors: the leak check and its death callback run
// at exit, after them.
char g_crash_path[512];
Bytes* const g_current = new Bytes;  // reachable from a global: not a leak

// Writes the input being run when the process dies of an escaped exception or of a sanitizer
// report (the sanitizers' death callback).
void save_current() {
  if (std::FILE* f = std::fopen(g_crash_path, "wb")) {
    if (!g_current->empty()) std::fwrite(g_current->data(), 1, g_current->size(), f);
    std::fclose(f);
  }
}

void run(const Bytes& b) {
  *g_current = b;
  LLVMFuzzerTestOneInput(b.data(), b.size());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " CORPUS_DIR [SECONDS] [SEED]\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  const double secs = argc > 2 ? std::atof(argv[2]) : 10.0;
  Rng rng{argc > 3 ? std::strtoull(argv[3], nullptr, 10) | 1u : 0x5eedULL};
  const std::string name = std::filesystem::path(argv[0]).filename().string();
  std::snprintf(g_crash_path, sizeof g_crash_path, "replay-crash-%s", name.c_str());
  std::set_terminate([] {
    save_current();
    std::cerr << "replay: an exception escaped the harness; input in " << g_crash_path << "\n";
    std::abort();
  });
  std::vector<Bytes> corpus;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    std::ifstream f(e.path(), std::ios::binary);
    corpus.emplace_back(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  }
  if (ec || corpus.empty()) {
    std::cerr << "replay: no seed files in the corpus directory '" << dir.string() << "'"
              << (ec ? " (" + ec.message() + ")" : std::string()) << "\n";
    return 2;
  }
  std::sort(corpus.begin(), corpus.end());  // the order of the directory is not the same everywhere
#ifdef SG_HAVE_SANITIZER_CALLBACK
  __sanitizer_set_death_callback([] {
    save_current();
    std::fprintf(stderr, "replay: input in %s\n", g_crash_path);
  });
#endif
  for (const Bytes& b : corpus) run(b);
  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t n = 0;
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < secs) {
    for (int k = 0; k < 16; ++k, ++n) run(mutate(corpus[rng.below(corpus.size())], rng, corpus));
  }
  std::cout << name << ": " << corpus.size() << " seeds and " << n << " mutations in " << secs
            << " s, no failure\n";
  return 0;
}
