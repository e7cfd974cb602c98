// Command-line plumbing for the hawor tools: option parsing, JSON output, error reporting.
// No algorithm lives here; each subcommand reads its inputs, calls include/hawor, prints.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/io/json.hpp"

namespace hawor_cli {

/// Thrown for usage errors (exit code 2); hawor::Error and others exit with 1.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `--name value` and `--flag` options after a subcommand. Unknown options are errors.
class Args {
 public:
  /// valued: options that take a value; flags: options that do not.
  Args(int argc, char** argv, int first, const std::set<std::string>& valued,
       const std::set<std::string>& flags) {
    for (int i = first; i < argc; ++i) {
      std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        help_ = true;
        continue;
      }
      if (a.rfind("--", 0) != 0) {
        positional_.push_back(a);
        continue;
      }
      std::string value;
      bool has_inline = false;
      const auto eq = a.find('=');
      if (eq != std::string::npos) {
        value = a.substr(eq + 1);
        a = a.substr(0, eq);
        has_inline = true;
      }
      const std::string key = a.substr(2);
      if (valued.count(key)) {
        if (!has_inline) {
          if (i + 1 >= argc) throw UsageError("option --" + key + " needs a value");
          value = argv[++i];
        }
        values_[key] = value;
        all_[key].push_back(value);
      } else if (flags.count(key)) {
        if (has_inline) throw UsageError("option --" + key + " takes no value");
        flags_.insert(key);
      } else {
        throw UsageError("unknown option --" + key);
      }
    }
  }
  bool help() const { return help_; }
  /// Every value a repeatable option was given, in order (get() keeps the last).
  std::vector<std::string> all(const std::string& k) const {
    auto it = all_.find(k);
    return it == all_.end() ? std::vector<std::string>() : it->second;
  }
  bool has(const std::string& k) const { return values_.count(k) || flags_.count(k); }
  bool flag(const std::string& k) const { return flags_.count(k) != 0; }
  const std::vector<std::string>& positional() const { return positional_; }
  std::string required(const std::string& k) const {
    auto it = values_.find(k);
    if (it == values_.end()) throw UsageError("missing required option --" + k);
    return it->second;
  }
  std::string get(const std::string& k, const std::string& fallback) const {
    auto it = values_.find(k);
    return it == values_.end() ? fallback : it->second;
  }
  double number(const std::string& k, double fallback) const {
    auto it = values_.find(k);
    if (it == values_.end()) return fallback;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v))
      throw UsageError("option --" + k + " expects a finite number, got '" + it->second + "'");
    return v;
  }
  /// Comma-separated numbers, e.g. --intrinsics fx,fy,cx,cy.
  std::vector<double> numbers(const std::string& k, size_t expected) const {
    std::vector<double> out;
    std::stringstream ss(required(k));
    std::string item;
    while (std::getline(ss, item, ',')) {
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      if (end == item.c_str() || *end != '\0' || !std::isfinite(v))
        throw UsageError("option --" + k + ": '" + item + "' is not a finite number");
      out.push_back(v);
    }
    if (expected && out.size() != expected)
      throw UsageError("option --" + k + " expects " + std::to_string(expected) +
                       " comma-separated numbers");
    return out;
  }

 private:
  bool help_ = false;
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> all_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
};

/// A flat JSON object printed on one line; doubles with 17 significant digits, NaN as null.
class JsonObject {
 public:
  JsonObject& num(const std::string& k, double v) {
    char buf[64];
    if (std::isfinite(v))
      std::snprintf(buf, sizeof buf, "%.17g", v);
    else
      std::snprintf(buf, sizeof buf, "null");
    items_.push_back(quote(k) + ": " + buf);
    return *this;
  }
  JsonObject& integer(const std::string& k, long long v) {
    items_.push_back(quote(k) + ": " + std::to_string(v));
    return *this;
  }
  JsonObject& str(const std::string& k, const std::string& v) {
    items_.push_back(quote(k) + ": " + quote(v));
    return *this;
  }
  JsonObject& strings(const std::string& k, const std::vector<std::string>& v) {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + quote(v[i]);
    items_.push_back(quote(k) + ": " + s + "]");
    return *this;
  }
  JsonObject& raw(const std::string& k, const std::string& json) {
    items_.push_back(quote(k) + ": " + json);
    return *this;
  }
  std::string dump() const {
    std::string s = "{";
    for (size_t i = 0; i < items_.size(); ++i) s += (i ? ", " : "") + items_[i];
    return s + "}";
  }
  static std::string quote(const std::string& s) { return hawor::jsonQuote(s); }

 private:
  std::vector<std::string> items_;
};

}  // namespace hawor_cli
