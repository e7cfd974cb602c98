// hawor/io/json.hpp — a small, strict JSON (RFC 8259) reader for the JSON parts of file formats
// (the glTF chunk of a .glb). No dependency; meant for untrusted input:
//   * nesting depth, input size and the number of values are capped (JsonLimits), so a hostile
//     document can neither overflow the stack nor allocate without bound;
//   * the whole input must be one value (surrounding whitespace allowed); errors name `what`, the
//     byte offset and what was expected;
//   * numbers follow the JSON grammar and are converted with the classic ("C") locale, correctly
//     rounded to double whatever the program's locale; out-of-range numbers are errors;
//   * strings: escapes decoded to UTF-8 (surrogate pairs joined, lone surrogates refused), raw
//     control characters refused, other bytes passed through;
//   * duplicate keys in one object are refused (glTF requires unique keys).
// Writing: jsonQuote() makes a JSON string literal (the writers of the CLI and the synthetic
// generator build their small documents with it).
// Thread-safety: a JsonValue is a plain value; parseJson has no shared state.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

#include "../common.hpp"

namespace hawor {

/// A JSON string literal for s: quotes, backslash escapes for '"' and '\\', \\u00XX for control
/// characters; other bytes (UTF-8) pass through.
inline std::string jsonQuote(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      o += b;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

/// Resource limits of parseJson.
struct JsonLimits {
  size_t maxBytes = size_t(64) << 20;  ///< input size
  int maxDepth = 64;                   ///< nesting of arrays / objects
  size_t maxValues = size_t(1) << 21;  ///< values of any kind (each costs ~100 bytes in memory)
};

/// One JSON value. Objects keep their members in document order.
class JsonValue {
 public:
  enum class Type { Null, Bool, Number, String, Array, Object };

  Type type() const { return type_; }
  bool isNull() const { return type_ == Type::Null; }
  bool isBool() const { return type_ == Type::Bool; }
  bool isNumber() const { return type_ == Type::Number; }
  bool isString() const { return type_ == Type::String; }
  bool isArray() const { return type_ == Type::Array; }
  bool isObject() const { return type_ == Type::Object; }

  static const char* typeName(Type t) {
    switch (t) {
      case Type::Null: return "null";
      case Type::Bool: return "a boolean";
      case Type::Number: return "a number";
      case Type::String: return "a string";
      case Type::Array: return "an array";
      case Type::Object: return "an object";
    }
    return "?";
  }

  /// Typed access; `what` names the value (file and path) in the error.
  bool asBool(const std::string& what) const {
    expect(Type::Bool, what);
    return bool_;
  }
  double asNumber(const std::string& what) const {
    expect(Type::Number, what);
    return number_;
  }
  const std::string& asString(const std::string& what) const {
    expect(Type::String, what);
    return string_;
  }
  /// Elements of an array.
  const std::vector<JsonValue>& items(const std::string& what) const {
    expect(Type::Array, what);
    return children_;
  }
  /// Member names and values of an object (same length, document order).
  const std::vector<std::string>& keys(const std::string& what) const {
    expect(Type::Object, what);
    return keys_;
  }
  const std::vector<JsonValue>& values(const std::string& what) const {
    expect(Type::Object, what);
    return children_;
  }
  /// The member `key` of an object, or nullptr when absent (or when this is not an object).
  const JsonValue* find(const std::string& key) const {
    if (type_ != Type::Object) return nullptr;
    for (size_t i = 0; i < keys_.size(); ++i) {
      if (keys_[i] == key) return &children_[i];
    }
    return nullptr;
  }
  /// Number of elements (array) or members (object); 0 otherwise.
  size_t size() const { return type_ == Type::Array || type_ == Type::Object ? children_.size() : 0; }

  static JsonValue makeNull() { return JsonValue(); }
  static JsonValue makeBool(bool b) {
    JsonValue v;
    v.type_ = Type::Bool;
    v.bool_ = b;
    return v;
  }
  static JsonValue makeNumber(double d) {
    JsonValue v;
    v.type_ = Type::Number;
    v.number_ = d;
    return v;
  }
  static JsonValue makeString(std::string s) {
    JsonValue v;
    v.type_ = Type::String;
    v.string_ = std::move(s);
    return v;
  }
  static JsonValue makeArray(std::vector<JsonValue> items) {
    JsonValue v;
    v.type_ = Type::Array;
    v.children_ = std::move(items);
    return v;
  }
  /// An object; throws hawor::Error on duplicate keys or mismatched lengths.
  static JsonValue makeObject(std::vector<std::string> keys, std::vector<JsonValue> values,
                              const std::string& what = "JSON object") {
    if (keys.size() != values.size()) throw Error(what + ": keys and values differ in number");
    std::vector<const std::string*> sorted;
    sorted.reserve(keys.size());
    for (const auto& k : keys) sorted.push_back(&k);
    std::sort(sorted.begin(), sorted.end(),
              [](const std::string* a, const std::string* b) { return *a < *b; });
    for (size_t i = 1; i < sorted.size(); ++i) {
      if (*sorted[i] == *sorted[i - 1]) throw Error(what + ": duplicate key \"" + *sorted[i] + "\"");
    }
    JsonValue v;
    v.type_ = Type::Object;
    v.keys_ = std::move(keys);
    v.children_ = std::move(values);
    return v;
  }

 private:
  void expect(Type t, const std::string& what) const {
    if (type_ != t) throw Error(what + " must be " + typeName(t) + ", found " + typeName(type_));
  }

  Type type_ = Type::Null;
  bool bool_ = false;
  double number_ = 0.0;
  std::string string_;
  std::vector<std::string> keys_;     // objects
  std::vector<JsonValue> children_;  // array elements or object values
};

namespace detail {

class JsonParser {
 public:
  JsonParser(const char* p, size_t n, const std::string& what, const JsonLimits& lim)
      : p_(p), n_(n), what_(what), lim_(lim) {
    num_.imbue(std::locale::classic());
  }

  JsonValue parseDocument() {
    if (n_ > lim_.maxBytes) {
      fail("is " + std::to_string(n_) + " bytes, over the limit of " + std::to_string(lim_.maxBytes));
    }
    skipWs();
    // A UTF-8 byte-order mark is not JSON; say so rather than "unexpected character".
    if (n_ >= 3 && static_cast<unsigned char>(p_[0]) == 0xEF && static_cast<unsigned char>(p_[1]) == 0xBB &&
        static_cast<unsigned char>(p_[2]) == 0xBF) {
      fail("starts with a UTF-8 byte-order mark, which JSON does not allow");
    }
    JsonValue v = parseValue(0);
    skipWs();
    if (i_ != n_) fail("unexpected " + describeHere() + " after the top-level value");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& msg) const { throw Error(what_ + ": " + msg); }
  [[noreturn]] void failAt(const std::string& msg) const {
    throw Error(what_ + ": " + msg + " at byte " + std::to_string(i_));
  }

  std::string describeHere() const {
    if (i_ >= n_) return "end of input";
    const unsigned char c = static_cast<unsigned char>(p_[i_]);
    if (c >= 0x20 && c < 0x7F) return std::string("character '") + static_cast<char>(c) + "'";
    return "byte 0x" + hex2(c);
  }
  static std::string hex2(unsigned c) {
    const char* d = "0123456789abcdef";
    return std::string{d[(c >> 4) & 15], d[c & 15]};
  }

  void skipWs() {
    while (i_ < n_) {
      const char c = p_[i_];
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
        ++i_;
      } else {
        break;
      }
    }
  }

  void countValue() {
    if (++values_ > lim_.maxValues) {
      fail("holds more than " + std::to_string(lim_.maxValues) + " values (limit)");
    }
  }

  JsonValue parseValue(int depth) {
    if (i_ >= n_) failAt("unexpected end of input, expected a value");
    countValue();
    const char c = p_[i_];
    switch (c) {
      case '{': return parseObject(depth + 1);
      case '[': return parseArray(depth + 1);
      case '"': return JsonValue::makeString(parseString());
      case 't': literal("true"); return JsonValue::makeBool(true);
      case 'f': literal("false"); return JsonValue::makeBool(false);
      case 'n': literal("null"); return JsonValue::makeNull();
      default:
        if (c == '-' || (c >= '0' && c <= '9')) return JsonValue::makeNumber(parseNumber());
        failAt("unexpected " + describeHere() + ", expected a value");
    }
  }

  void literal(const char* word) {
    size_t k = 0;
    for (; word[k]; ++k) {
      if (i_ + k >= n_ || p_[i_ + k] != word[k]) failAt(std::string("invalid literal, expected '") + word + "'");
    }
    i_ += k;
  }

  void enter(int depth) {
    if (depth > lim_.maxDepth) {
      failAt("nesting deeper than " + std::to_string(lim_.maxDepth) + " levels (limit)");
    }
  }

  JsonValue parseArray(int depth) {
    enter(depth);
    ++i_;  // '['
    std::vector<JsonValue> items;
    skipWs();
    if (i_ < n_ && p_[i_] == ']') {
      ++i_;
      return JsonValue::makeArray(std::move(items));
    }
    for (;;) {
      skipWs();
      items.push_back(parseValue(depth));
      skipWs();
      if (i_ >= n_) failAt("unexpected end of input in an array, expected ',' or ']'");
      if (p_[i_] == ',') {
        ++i_;
        continue;
      }
      if (p_[i_] == ']') {
        ++i_;
        return JsonValue::makeArray(std::move(items));
      }
      failAt("unexpected " + describeHere() + " in an array, expected ',' or ']'");
    }
  }

  JsonValue parseObject(int depth) {
    enter(depth);
    const size_t start = i_;
    ++i_;  // '{'
    std::vector<std::string> keys;
    std::vector<JsonValue> values;
    skipWs();
    if (i_ < n_ && p_[i_] == '}') {
      ++i_;
      return JsonValue::makeObject(std::move(keys), std::move(values));
    }
    for (;;) {
      skipWs();
      if (i_ >= n_ || p_[i_] != '"') failAt("unexpected " + describeHere() + " in an object, expected a key string");
      keys.push_back(parseString());
      skipWs();
      if (i_ >= n_ || p_[i_] != ':') failAt("unexpected " + describeHere() + " after an object key, expected ':'");
      ++i_;
      skipWs();
      values.push_back(parseValue(depth));
      skipWs();
      if (i_ >= n_) failAt("unexpected end of input in an object, expected ',' or '}'");
      if (p_[i_] == ',') {
        ++i_;
        continue;
      }
      if (p_[i_] == '}') {
        ++i_;
        return JsonValue::makeObject(std::move(keys), std::move(values),
                                     what_ + ": object at byte " + std::to_string(start));
      }
      failAt("unexpected " + describeHere() + " in an object, expected ',' or '}'");
    }
  }

  unsigned hex4() {
    if (n_ - i_ < 4) failAt("truncated \\u escape");
    unsigned v = 0;
    for (int k = 0; k < 4; ++k) {
      const char c = p_[i_++];
      v <<= 4;
      if (c >= '0' && c <= '9') {
        v |= static_cast<unsigned>(c - '0');
      } else if (c >= 'a' && c <= 'f') {
        v |= static_cast<unsigned>(c - 'a' + 10);
      } else if (c >= 'A' && c <= 'F') {
        v |= static_cast<unsigned>(c - 'A' + 10);
      } else {
        --i_;
        failAt("invalid hex digit in a \\u escape");
      }
    }
    return v;
  }

  static void appendUtf8(std::string& s, unsigned cp) {
    if (cp < 0x80) {
      s += static_cast<char>(cp);
    } else if (cp < 0x800) {
      s += static_cast<char>(0xC0 | (cp >> 6));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      s += static_cast<char>(0xE0 | (cp >> 12));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      s += static_cast<char>(0xF0 | (cp >> 18));
      s += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }

  std::string parseString() {
    ++i_;  // opening quote
    std::string s;
    for (;;) {
      if (i_ >= n_) failAt("unterminated string");
      const unsigned char c = static_cast<unsigned char>(p_[i_]);
      if (c == '"') {
        ++i_;
        return s;
      }
      if (c < 0x20) failAt("raw control character 0x" + hex2(c) + " in a string");
      if (c != '\\') {
        s += static_cast<char>(c);
        ++i_;
        continue;
      }
      ++i_;
      if (i_ >= n_) failAt("unterminated escape in a string");
      const char e = p_[i_++];
      switch (e) {
        case '"': s += '"'; break;
        case '\\': s += '\\'; break;
        case '/': s += '/'; break;
        case 'b': s += '\b'; break;
        case 'f': s += '\f'; break;
        case 'n': s += '\n'; break;
        case 'r': s += '\r'; break;
        case 't': s += '\t'; break;
        case 'u': {
          unsigned cp = hex4();
          if (cp >= 0xDC00 && cp <= 0xDFFF) failAt("lone low surrogate in a \\u escape");
          if (cp >= 0xD800 && cp <= 0xDBFF) {
            if (n_ - i_ < 2 || p_[i_] != '\\' || p_[i_ + 1] != 'u') failAt("high surrogate not followed by a low one");
            i_ += 2;
            const unsigned lo = hex4();
            if (lo < 0xDC00 || lo > 0xDFFF) failAt("high surrogate not followed by a low one");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
          }
          appendUtf8(s, cp);
          break;
        }
        default:
          --i_;
          failAt("invalid escape '\\" + std::string(1, e) + "' in a string");
      }
    }
  }

  double parseNumber() {
    const size_t start = i_;
    auto digit = [&](size_t k) { return k < n_ && p_[k] >= '0' && p_[k] <= '9'; };
    if (p_[i_] == '-') ++i_;
    if (!digit(i_)) failAt("invalid number (no digits)");
    if (p_[i_] == '0') {
      ++i_;
      if (digit(i_)) failAt("invalid number (leading zero)");
    } else {
      while (digit(i_)) ++i_;
    }
    if (i_ < n_ && p_[i_] == '.') {
      ++i_;
      if (!digit(i_)) failAt("invalid number (no digits after '.')");
      while (digit(i_)) ++i_;
    }
    if (i_ < n_ && (p_[i_] == 'e' || p_[i_] == 'E')) {
      ++i_;
      if (i_ < n_ && (p_[i_] == '+' || p_[i_] == '-')) ++i_;
      if (!digit(i_)) failAt("invalid number (no exponent digits)");
      while (digit(i_)) ++i_;
    }
    const std::string text(p_ + start, i_ - start);
    // The classic-locale stream converts with strtod semantics in the "C" locale.
    num_.clear();
    num_.str(text);
    double v = 0.0;
    num_ >> v;
    if (num_.fail() || !std::isfinite(v)) {
      // Some standard libraries flag underflow (|x| < DBL_MIN) as a failure: such a number is 0
      // for every purpose here. Overflow is an error.
      if (underflows(text)) return text[0] == '-' ? -0.0 : 0.0;
      i_ = start;
      failAt("number " + text.substr(0, 40) + " is out of the range of a double");
    }
    return v;
  }

  /// True when a valid JSON number is zero or its magnitude is below 1e-300, decided from its
  /// digits: the first non-zero digit has decimal exponent intDigits − 1 − z + e (z = its index
  /// among the mantissa digits, e = the written exponent).
  static bool underflows(const std::string& t) {
    size_t k = t[0] == '-' ? 1 : 0;
    long intDigits = 0, index = 0, z = -1;
    bool dot = false;
    for (; k < t.size() && t[k] != 'e' && t[k] != 'E'; ++k) {
      if (t[k] == '.') {
        dot = true;
        continue;
      }
      if (!dot) ++intDigits;
      if (z < 0 && t[k] != '0') z = index;
      ++index;
    }
    if (z < 0) return true;
    long e = 0;
    bool neg = false;
    for (size_t q = k + 1; q < t.size(); ++q) {
      if (t[q] == '-') neg = true;
      if (t[q] >= '0' && t[q] <= '9') e = std::min<long>(e * 10 + (t[q] - '0'), 1000000);
    }
    return intDigits - 1 - z + (neg ? -e : e) < -300;
  }

  const char* p_;
  size_t n_;
  size_t i_ = 0;
  size_t values_ = 0;
  const std::string& what_;
  JsonLimits lim_;
  std::istringstream num_;
};

}  // namespace detail

/// Parses the JSON text p[0, n). `what` names the document in errors (e.g. "hand.glb: JSON chunk").
inline JsonValue parseJson(const char* p, size_t n, const std::string& what = "JSON",
                           const JsonLimits& limits = {}) {
  if (p == nullptr && n != 0) throw Error(what + ": null input");
  detail::JsonParser parser(p == nullptr ? "" : p, n, what, limits);
  return parser.parseDocument();
}

inline JsonValue parseJson(const std::string& text, const std::string& what = "JSON",
                           const JsonLimits& limits = {}) {
  return parseJson(text.data(), text.size(), what, limits);
}

}  // namespace hawor
