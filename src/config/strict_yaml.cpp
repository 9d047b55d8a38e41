#include "stairguide/config/strict_yaml.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <sstream>
#include <vector>

namespace stairguide {

std::string read_small_file(const std::string& path, std::size_t max_bytes, const char* what) {
  if (path.empty()) throw InputFileError(std::string(what) + ": no file name given");
  // O_NONBLOCK: opening a FIFO with no writer must not wait for one. The file's kind is checked
  // on the open descriptor, so what is read is what was checked.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw InputFileError(path + ": cannot open " + what + " (" + std::strerror(err) + ")");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw InputFileError(path + ": cannot stat " + what + " (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw InputFileError(path + ": is a directory, not a " + what);
  if (!S_ISREG(st.st_mode)) {
    const char* kind = S_ISFIFO(st.st_mode)   ? "a FIFO"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    throw InputFileError(path + ": " + what + " is " + kind + ", not a regular file; refused");
  }
  auto too_big = [&]() {
    return InputFileError(path + ": " + what + " is bigger than " + std::to_string(max_bytes) +
                          " bytes; refused (not a file this program writes or reads)");
  };
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) throw too_big();
  // The size may change while reading (or be 0, as /proc files say): read at most one byte more
  // than the limit.
  std::string text;
  text.resize(std::min<std::size_t>(max_bytes + 1, static_cast<std::size_t>(st.st_size) + 4096));
  std::size_t got = 0;
  for (;;) {
    if (got == text.size()) {
      if (text.size() > max_bytes) break;
      text.resize(std::min(max_bytes + 1, text.size() * 2));
    }
    const ssize_t n = ::read(fd, &text[got], text.size() - got);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputFileError(path + ": read error on " + what + " (" + std::strerror(errno) + ")");
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  if (got > max_bytes) throw too_big();
  text.resize(got);
  return text;
}

namespace {

struct Refusal {
  int line;  ///< 0-based, -1 when unknown
  std::string what;
};

/// Walks the parser's events: counts nodes and depth, names every key by its path, and refuses
/// a key given twice in one mapping and a second document.
class Checker : public YAML::EventHandler {
 public:
  explicit Checker(const YamlLimits& limits) : limits_(limits) {}

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1)
      throw Refusal{mark.line,
                    "a second YAML document ('---' or '...' followed by more); one document expected"};
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override {
    static const std::string null_key = "~";
    leaf(mark, null_key);
  }
  // An alias repeats a whole subtree for free (a few lines can stand for billions of nodes to
  // walk), and no file read here uses one.
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    throw Refusal{mark.line, "YAML aliases (*name) are not accepted here"};
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    leaf(mark, value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    open(mark, false);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    open(mark, true);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    bool map = false;
    bool want_key = true;             // map: the next node is a key
    std::string key;                  // map: the current key
    std::size_t index = 0;            // sequence: the current item
    std::map<std::string, int> seen;  // map: key -> 0-based line
  };

  void count(const YAML::Mark& mark) {
    if (++nodes_ > limits_.max_nodes)
      throw Refusal{mark.line, "more than " + std::to_string(limits_.max_nodes) +
                                   " YAML nodes; refused (far more than this file ever holds)"};
  }

  std::string path() const {
    std::string p;
    for (const Frame& f : stack_) {
      if (f.map) {
        if (f.want_key) break;
        p += (p.empty() ? "" : ".") + f.key;
      } else {
        p += "[" + std::to_string(f.index) + "]";
      }
    }
    return p;
  }

  /// A key is a plain value: the files read here have no other.
  bool as_key(const YAML::Mark& mark, const std::string& k) {
    if (stack_.empty() || !stack_.back().map || !stack_.back().want_key) return false;
    Frame& f = stack_.back();
    const auto it = f.seen.find(k);
    if (it != f.seen.end()) {
      f.key = k;
      f.want_key = false;
      throw Refusal{mark.line, "key '" + path() + "' given twice (first on line " +
                                   std::to_string(it->second + 1) + "): the later value would be ignored"};
    }
    f.seen.emplace(k, mark.line);
    f.key = k;
    f.want_key = false;
    return true;
  }

  void value_done() {
    if (stack_.empty()) return;
    Frame& f = stack_.back();
    if (f.map)
      f.want_key = true;
    else
      ++f.index;
  }

  void leaf(const YAML::Mark& mark, const std::string& value) {
    count(mark);
    if (as_key(mark, value)) return;
    value_done();
  }

  void open(const YAML::Mark& mark, bool map) {
    count(mark);
    if (!stack_.empty() && stack_.back().map && stack_.back().want_key)
      throw Refusal{mark.line,
                    "a mapping key must be a plain value (found a collection) under '" + path() + "'"};
    if (static_cast<int>(stack_.size()) >= limits_.max_depth)
      throw Refusal{mark.line,
                    "nested deeper than " + std::to_string(limits_.max_depth) + " levels; refused"};
    stack_.emplace_back();
    stack_.back().map = map;
  }
  void close() {
    if (!stack_.empty()) stack_.pop_back();
    value_done();
  }

  YamlLimits limits_;
  std::vector<Frame> stack_;
  std::size_t nodes_ = 0;
  int documents_ = 0;
};

}  // namespace

YAML::Node load_strict_yaml(const std::string& text, const std::string& name, const YamlLimits& limits) {
  auto at = [&](int line) { return line >= 0 ? name + ":" + std::to_string(line + 1) : name; };
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    Checker checker(limits);
    while (parser.HandleNextDocument(checker)) {
    }
    return YAML::Load(text);
  } catch (const Refusal& r) {
    throw InputFileError(at(r.line) + ": " + r.what);
  } catch (const YAML::ParserException& e) {
    throw InputFileError(at(e.mark.line) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw InputFileError(at(e.mark.line) + ": YAML error: " + e.msg);
  }
}

}  // namespace stairguide
