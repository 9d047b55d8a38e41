#include "stairguide/config/config_loader.hpp"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <type_traits>

#include "stairguide/config/strict_yaml.hpp"

#ifndef STAIRGUIDE_SOURCE_DIR
#define STAIRGUIDE_SOURCE_DIR ""
#endif

namespace stairguide {
namespace {

std::string fmt_num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

class Reader {
 public:
  Reader(const std::string& file, ConfigLoadReport* report) : file_(file), report_(report) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& key, const std::string& what) const {
    std::string loc = file_;
    if (at.IsDefined() && at.Mark().line >= 0) loc += ":" + std::to_string(at.Mark().line + 1);
    throw ConfigError(loc + ": key '" + key + "': " + what);
  }

  void root(const YAML::Node& doc, PipelineConfig& c) {
    // yaml-cpp's Node::operator= writes through to the referenced node, so the current node is
    // kept on a stack of copies (copy construction rebinds) instead of being reassigned.
    if (doc.IsNull()) {
      stack_.emplace_back(YAML::NodeType::Map);
    } else if (!doc.IsMap()) {
      throw ConfigError(file_ + ":" + std::to_string(doc.Mark().line + 1) +
                        ": the top level must be a mapping of sections");
    } else {
      stack_.push_back(doc);
    }
    check_unknown(stack_.back(), "");
    c.visit(*this);
  }

  template <class S>
  void section(const char* name, const char*, S& s) {
    const std::string saved_prefix = prefix_;
    const YAML::Node sub = static_cast<const YAML::Node&>(stack_.back())[name];
    prefix_ = saved_prefix + name + ".";
    if (!sub.IsDefined() || sub.IsNull()) {
      stack_.emplace_back(YAML::NodeType::Map);
    } else if (!sub.IsMap()) {
      fail(sub, saved_prefix + name, "must be a mapping of keys");
    } else {
      stack_.push_back(sub);
      check_unknown(sub, prefix_);
    }
    s.visit(*this);
    stack_.pop_back();
    prefix_ = saved_prefix;
  }

  /// 1-based line of every key the file gives, by full name ("floor.tilt_min_deg").
  const std::map<std::string, int>& lines() const { return lines_; }

  template <class T>
  void num(T& field, const char* key, Unit unit, double lo, double hi, const char*) {
    const YAML::Node n = static_cast<const YAML::Node&>(stack_.back())[key];
    const std::string full = prefix_ + key;
    if (!present(n, full)) return;
    if (!n.IsScalar()) fail(n, full, "expected a number, found a " + kind(n));
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, full, "expected a number, found '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(n, full, "expected a finite number, found '" + n.Scalar() + "'");
    if (std::is_integral<T>::value && v != std::floor(v))
      fail(n, full, "expected a whole number, found '" + n.Scalar() + "'");
    if (v < lo || v > hi) {
      std::string u = unit_name(unit);
      fail(n, full,
           "value " + n.Scalar() + " is out of range [" + fmt_num(lo) + ", " + fmt_num(hi) + "]" +
               (u.empty() ? "" : " " + u));
    }
    if (std::is_integral<T>::value)
      field = static_cast<T>(std::llround(v));
    else
      field = static_cast<T>(v * unit_to_si(unit));
  }

  void flag(bool& field, const char* key, const char*) {
    const YAML::Node n = static_cast<const YAML::Node&>(stack_.back())[key];
    const std::string full = prefix_ + key;
    if (!present(n, full)) return;
    if (!n.IsScalar()) fail(n, full, "expected true or false, found a " + kind(n));
    const std::string s = n.Scalar();
    if (s == "true" || s == "yes" || s == "on")
      field = true;
    else if (s == "false" || s == "no" || s == "off")
      field = false;
    else
      fail(n, full, "expected true or false, found '" + s + "'");
  }

  void text(std::string& field, const char* key, std::initializer_list<const char*> allowed, const char*) {
    const YAML::Node n = static_cast<const YAML::Node&>(stack_.back())[key];
    const std::string full = prefix_ + key;
    if (!present(n, full)) return;
    if (!n.IsScalar()) fail(n, full, "expected a string, found a " + kind(n));
    const std::string s = n.Scalar();
    if (allowed.size() > 0) {
      bool ok = false;
      std::string list;
      for (const char* a : allowed) {
        ok = ok || s == a;
        list += (list.empty() ? "" : ", ") + std::string(a);
      }
      if (!ok) fail(n, full, "'" + s + "' is not one of: " + list);
    }
    field = s;
  }

 private:
  bool present(const YAML::Node& n, const std::string& full) {
    if (n.IsDefined() && n.Mark().line >= 0) lines_[full] = n.Mark().line + 1;
    if (n.IsDefined() && !n.IsNull()) return true;
    if (n.IsDefined() && n.IsNull()) fail(n, full, "has no value");
    if (report_) report_->missing_keys.push_back(full);
    return false;
  }

  static std::string kind(const YAML::Node& n) {
    if (n.IsMap()) return "mapping";
    if (n.IsSequence()) return "list";
    return "value";
  }

  /// Names every key of `map` that the config does not know, with the known ones as a hint.
  void check_unknown(const YAML::Node& map, const std::string& prefix) {
    std::set<std::string> known;
    KeyLister lister{known};
    if (prefix.empty()) {
      PipelineConfig tmp;
      tmp.visit(lister);
    } else {
      PipelineConfig tmp;
      SectionKeyLister sl{prefix.substr(0, prefix.size() - 1), known};
      tmp.visit(sl);
    }
    for (auto it = map.begin(); it != map.end(); ++it) {
      const std::string k = it->first.as<std::string>("");
      if (!known.count(k)) {
        std::string hint;
        for (const auto& kn : known) hint += (hint.empty() ? "" : ", ") + kn;
        fail(it->first, prefix + k, "unknown key (known here: " + hint + ")");
      }
    }
  }

  struct KeyLister {  // top-level: section names
    std::set<std::string>& out;
    template <class T>
    void num(T&, const char*, Unit, double, double, const char*) {}
    void flag(bool&, const char*, const char*) {}
    void text(std::string&, const char*, std::initializer_list<const char*>, const char*) {}
    template <class S>
    void section(const char* name, const char*, S&) {
      out.insert(name);
    }
  };
  struct SectionKeyLister {  // keys of one section
    std::string want;
    std::set<std::string>& out;
    bool inside = false;
    template <class T>
    void num(T&, const char* k, Unit, double, double, const char*) {
      add(k);
    }
    void flag(bool&, const char* k, const char*) { add(k); }
    void text(std::string&, const char* k, std::initializer_list<const char*>, const char*) { add(k); }
    template <class S>
    void section(const char* name, const char*, S& s) {
      inside = want == name;
      s.visit(*this);
      inside = false;
    }
    void add(const char* k) {
      if (inside) out.insert(k);
    }
  };

  std::string file_;
  ConfigLoadReport* report_;
  std::vector<YAML::Node> stack_;
  std::string prefix_;
  std::map<std::string, int> lines_;
};

class Writer {
 public:
  std::ostringstream os;
  template <class S>
  void section(const char* name, const char* doc, S& s) {
    os << "\n# " << doc << "\n" << name << ":\n";
    s.visit(*this);
  }
  template <class T>
  void num(T& f, const char* key, Unit unit, double lo, double hi, const char* doc) {
    double v = static_cast<double>(f);
    if (!std::is_integral<T>::value) v /= unit_to_si(unit);
    std::ostringstream val;
    val.precision(6);
    val << v;
    std::string u = unit_name(unit);
    line(key, val.str(),
         std::string(doc) + " [" + fmt_num(lo) + ".." + fmt_num(hi) + (u.empty() ? "" : " " + u) + "]");
  }
  void flag(bool& f, const char* key, const char* doc) { line(key, f ? "true" : "false", doc); }
  void text(std::string& f, const char* key, std::initializer_list<const char*> allowed, const char* doc) {
    std::string d = doc;
    if (allowed.size()) {
      d += " (";
      bool first = true;
      for (const char* a : allowed) {
        d += (first ? "" : "|") + std::string(a);
        first = false;
      }
      d += ")";
    }
    line(key, "\"" + f + "\"", d);
  }

 private:
  void line(const char* key, const std::string& value, const std::string& doc) {
    std::string l = std::string("  ") + key + ": " + value;
    if (l.size() < 40) l.resize(40, ' ');
    os << l << " # " << doc << "\n";
  }
};

// Whether a config candidate is there, by stat alone: opening it to see would block for ever on a
// FIFO with no writer. Anything there but a directory is chosen; load_config then reads a regular
// file or names what else it is (a FIFO, a device) and refuses it.
bool config_candidate_exists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && !S_ISDIR(st.st_mode);
}

}  // namespace

// Bounds on a config file: the shipped one, every key commented, is about 25 kB and 700 nodes.
// A file many times that is not a config (a 5 MB flow list once took 1.3 GB to parse).
constexpr std::size_t kMaxConfigBytes = 1u << 20;
constexpr YamlLimits kConfigYamlLimits{20000, 8};

PipelineConfig load_config_text(const std::string& text, const std::string& name, ConfigLoadReport* report) {
  if (text.size() > kMaxConfigBytes)
    throw ConfigError(name + ": config is bigger than " + std::to_string(kMaxConfigBytes) +
                      " bytes; refused");
  YAML::Node doc;
  try {
    doc = load_strict_yaml(text, name, kConfigYamlLimits);
  } catch (const InputFileError& e) {
    throw ConfigError(e.what());
  }
  // A file with no keys at all (empty, blanks, comments only) is not a config that asks for the
  // defaults: it is an editor that truncated the file before writing it, or the wrong file.
  // Taken, it silently put every key back to its default (issue 41); an explicit `{}` still does.
  if (doc.IsNull())
    throw ConfigError(name +
                      ": the config is empty (no keys: only blank lines or comments); refused. Give at least "
                      "one section, or `{}` for every default");
  PipelineConfig c;
  Reader r(name, report);
  r.root(doc, c);
  const auto problems = find_inconsistencies(c);
  if (!problems.empty()) {
    // Named at the later of the two keys in the file (the one that made the pair wrong, as read).
    const auto& p = problems.front();
    std::string key = p.key_b;
    int line = -1;
    for (const std::string* k : {&p.key_a, &p.key_b}) {
      const auto it = r.lines().find(*k);
      if (it != r.lines().end() && it->second > line) {
        line = it->second;
        key = *k;
      }
    }
    throw ConfigError(name + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": key '" + key +
                      "': " + p.message);
  }
  return c;
}

PipelineConfig load_config(const std::string& path, ConfigLoadReport* report) {
  if (path.empty()) throw ConfigError("config: no file name given");
  std::string text;
  try {
    text = read_small_file(path, kMaxConfigBytes, "config file");
  } catch (const InputFileError& e) {
    throw ConfigError(e.what());
  }
  return load_config_text(text, path, report);
}

std::string dump_config_yaml(const PipelineConfig& config) {
  Writer w;
  w.os << "# stairguide configuration. Every tunable of the pipeline, with its unit in the key\n"
          "# and its range in brackets. Keys left out keep these defaults.\n";
  const_cast<PipelineConfig&>(config).visit(w);
  return w.os.str();
}

std::string first_config_path(const std::vector<std::string>& candidates) {
  for (const auto& c : candidates) {
    if (!c.empty() && config_candidate_exists(c)) return c;
  }
  return "";
}

std::string default_config_path() {
  if (const char* env = std::getenv("STAIRGUIDE_CONFIG"); env && *env) return env;
  std::vector<std::string> candidates{"/etc/stairguide/stairguide.yaml"};
  if (std::string(STAIRGUIDE_SOURCE_DIR).size())
    candidates.push_back(std::string(STAIRGUIDE_SOURCE_DIR) + "/config/stairguide.yaml");
  return first_config_path(candidates);
}

}  // namespace stairguide
