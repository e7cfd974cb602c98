// hawor/hand/pickle.hpp — a symbolic, NON-executing reader for Python pickles (protocols 0–5).
//
// Why: the MANO model files are Python-2 pickles (docs/design.md §3). Loading them with Python's pickle
// runs arbitrary code named in the file; this reader instead interprets every opcode into an
// inert value tree and never imports, calls or evaluates anything. Globals become names
// (`Global{module, name}`), REDUCE / NEWOBJ / OBJ / INST become records of "what would have been
// called with what", BUILD attaches its state to that record. A consumer (hand/mano_loader.hpp)
// then reads only the shapes it knows, against an allowlist of globals.
//
// Values live in an arena (`Document`) and refer to each other by index, so memo sharing and even
// cycles (a list appended to itself) are represented without reference counting or leaks. The
// usual Python semantics of mutation are kept: APPEND / SETITEM / BUILD change the node in place,
// so a memoised reference sees the change, as in Python.
//
// Hardening (every failure is a hawor::Error naming the problem and the byte offset of the
// opcode): unknown opcodes, stack underflow (also below an open MARK), opcodes needing a MARK
// without one, memo keys never stored, truncation anywhere, missing STOP, declared lengths larger
// than the remaining input (checked BEFORE allocating), nesting deeper than Limits::maxDepth (open
// MARKs and container depth), more nodes than Limits::maxNodes (default: proportional to the input
// size), integers beyond 64 bits, persistent IDs, extension codes and out-of-band buffers.
// Memory use is O(input size): each opcode creates at most one node and strings are bounded by the
// bytes they were read from.
//
// The value tree (Value, Document, Limits) is in pickle_value.hpp.
// Thread-safety: parse() is re-entrant; a Document is immutable after parsing.
#pragma once

#include "hawor/common.hpp"
#include "hawor/hand/pickle_value.hpp"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <locale>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace hawor {
namespace pickle {

/// The opcode interpreter. Use pickle::parse().
class Parser {
 public:
  Parser(const std::uint8_t* data, std::size_t size, const Limits& limits)
      : data_(data), size_(size), limits_(limits) {
    maxNodes_ = limits.maxNodes != 0 ? limits.maxNodes : size + 16;
  }

  Document run() {
    if (data_ == nullptr && size_ != 0) throw Error("pickle: null input buffer");
    while (true) {
      op_ = pos_;
      if (pos_ >= size_) fail("truncated input: no STOP opcode");
      const std::uint8_t code = data_[pos_++];
      if (step(code)) break;
    }
    doc_.end_ = pos_;
    return std::move(doc_);
  }

 private:
  // --- errors and raw reads ------------------------------------------------------------------
  [[noreturn]] void fail(const std::string& what) const {
    throw Error("pickle: " + what + " at byte offset " + std::to_string(op_));
  }
  void need(std::uint64_t n, const char* what) const {
    if (n > size_ - pos_) {
      fail(std::string("truncated input: ") + what + " needs " + std::to_string(n) +
           " bytes, only " + std::to_string(size_ - pos_) + " remain");
    }
  }
  std::uint64_t readLE(int bytes, const char* what) {
    need(static_cast<std::uint64_t>(bytes), what);
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(data_[pos_ + i]) << (8 * i);
    pos_ += static_cast<std::size_t>(bytes);
    return v;
  }
  std::int32_t readI32(const char* what) {
    const std::uint32_t u = static_cast<std::uint32_t>(readLE(4, what));
    std::int32_t s;
    std::memcpy(&s, &u, 4);
    return s;
  }
  // A text argument terminated by '\n' (the newline is consumed, not returned).
  std::string readLine(const char* what) {
    const void* nl = std::memchr(data_ + pos_, '\n', size_ - pos_);
    if (nl == nullptr) fail(std::string("truncated input: ") + what + " has no terminating newline");
    const std::size_t end = static_cast<std::size_t>(static_cast<const std::uint8_t*>(nl) - data_);
    std::string s(reinterpret_cast<const char*>(data_ + pos_), end - pos_);
    pos_ = end + 1;
    return s;
  }
  std::string readBytes(std::uint64_t n, const char* what) {
    need(n, what);  // before allocating: a declared length never exceeds what is left
    std::string s(reinterpret_cast<const char*>(data_ + pos_), static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return s;
  }

  // --- nodes and the stack -------------------------------------------------------------------
  std::uint32_t make(Kind k) {
    if (doc_.nodes_.size() >= maxNodes_) {
      fail("more than " + std::to_string(maxNodes_) + " values (limit)");
    }
    detail::Node n;
    n.kind = k;
    n.offset = op_;
    doc_.nodes_.push_back(std::move(n));
    return static_cast<std::uint32_t>(doc_.nodes_.size() - 1);
  }
  detail::Node& at(std::uint32_t i) { return doc_.nodes_[i]; }
  std::uint32_t makeString(Kind k, std::string s) {
    const std::uint32_t i = make(k);
    doc_.strings_.push_back(std::move(s));
    at(i).text = static_cast<std::uint32_t>(doc_.strings_.size() - 1);
    return i;
  }
  std::uint32_t makeInt(Kind k, std::int64_t v) {
    const std::uint32_t i = make(k);
    at(i).integer = v;
    return i;
  }
  std::uint32_t makeGlobal(std::string module, std::string name) {
    const std::uint32_t i = make(Kind::Global);
    doc_.strings_.push_back(std::move(module));
    at(i).text = static_cast<std::uint32_t>(doc_.strings_.size() - 1);
    doc_.strings_.push_back(std::move(name));
    at(i).name = static_cast<std::uint32_t>(doc_.strings_.size() - 1);
    return i;
  }
  // Raises the depth of `parent` to cover `child`, enforcing maxDepth.
  void cover(std::uint32_t parent, std::uint32_t child) {
    const std::uint32_t d = at(child).depth + 1;
    if (d > at(parent).depth) {
      if (d > limits_.maxDepth) {
        fail("values nested deeper than " + std::to_string(limits_.maxDepth) + " levels (limit)");
      }
      at(parent).depth = d;
    }
  }
  std::uint32_t makeContainer(Kind k, const std::uint32_t* items, std::size_t n) {
    const std::uint32_t i = make(k);
    at(i).depth = 1;
    at(i).items.assign(items, items + n);
    for (std::size_t j = 0; j < n; ++j) cover(i, items[j]);
    return i;
  }
  std::size_t base() const { return marks_.empty() ? 0 : marks_.back(); }
  void push(std::uint32_t v) { stack_.push_back(v); }
  std::uint32_t pop() {
    if (stack_.size() <= base()) fail("stack underflow");
    const std::uint32_t v = stack_.back();
    stack_.pop_back();
    return v;
  }
  std::uint32_t top() const {
    if (stack_.size() <= base()) fail("stack underflow");
    return stack_.back();
  }
  // Removes everything above the innermost MARK and the MARK itself; returns those items.
  std::vector<std::uint32_t> popMark() {
    if (marks_.empty()) fail("opcode needs a MARK but none is open");
    const std::size_t b = marks_.back();
    marks_.pop_back();
    std::vector<std::uint32_t> items(stack_.begin() + static_cast<std::ptrdiff_t>(b), stack_.end());
    stack_.resize(b);
    return items;
  }
  std::uint32_t memoGet(std::uint64_t key) const {
    const auto it = memo_.find(key);
    if (it == memo_.end()) fail("memo key " + std::to_string(key) + " was never stored");
    return it->second;
  }
  void memoPut(std::uint64_t key) { memo_[key] = top(); }

  // --- text arguments ------------------------------------------------------------------------
  static bool parseDecimal(const std::string& s, std::int64_t& out) {
    std::size_t i = 0;
    bool neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) neg = s[i++] == '-';
    if (i >= s.size()) return false;
    std::uint64_t v = 0;
    const std::uint64_t limit = neg ? std::uint64_t(1) << 63 : (std::uint64_t(1) << 63) - 1;
    for (; i < s.size(); ++i) {
      if (s[i] < '0' || s[i] > '9') return false;
      const std::uint64_t d = static_cast<std::uint64_t>(s[i] - '0');
      if (v > (limit - d) / 10) return false;
      v = v * 10 + d;
    }
    if (neg) {
      out = v == (std::uint64_t(1) << 63) ? std::numeric_limits<std::int64_t>::min()
                                           : -static_cast<std::int64_t>(v);
    } else {
      out = static_cast<std::int64_t>(v);
    }
    return true;
  }
  std::int64_t textInt(std::string s, bool allowL) {
    while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
    if (allowL && !s.empty() && s.back() == 'L') s.pop_back();
    std::int64_t v = 0;
    if (!parseDecimal(s, v)) fail("invalid or out-of-range (beyond 64 bits) integer '" + s + "'");
    return v;
  }
  std::uint64_t textMemoKey(const std::string& s) {
    const std::int64_t v = textInt(s, false);
    if (v < 0) fail("negative memo key");
    return static_cast<std::uint64_t>(v);
  }
  double textFloat(std::string s) {
    while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
    std::string low;
    for (char c : s) low.push_back(static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c));
    if (low == "nan" || low == "-nan" || low == "+nan") return std::numeric_limits<double>::quiet_NaN();
    if (low == "inf" || low == "+inf" || low == "infinity") return std::numeric_limits<double>::infinity();
    if (low == "-inf" || low == "-infinity") return -std::numeric_limits<double>::infinity();
    std::istringstream in(s);
    in.imbue(std::locale::classic());  // never the user's decimal comma
    double v = 0;
    in >> v;
    if (in.fail() || !(in >> std::ws).eof()) fail("invalid float literal '" + s + "'");
    return v;
  }
  static int hexDigit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  }
  // STRING's argument: a quoted Python-2 repr, decoded like codecs.escape_decode.
  std::string unquote(const std::string& s) {
    if (s.size() < 2 || s.front() != s.back() || (s.front() != '\'' && s.front() != '"')) {
      fail("the STRING opcode argument must be quoted");
    }
    std::string out;
    const std::size_t end = s.size() - 1;
    for (std::size_t i = 1; i < end; ++i) {
      const char c = s[i];
      if (c != '\\') {
        out.push_back(c);
        continue;
      }
      if (++i >= end) fail("trailing backslash in STRING argument");
      const char e = s[i];
      switch (e) {
        case '\n': break;
        case '\\': out.push_back('\\'); break;
        case '\'': out.push_back('\''); break;
        case '"': out.push_back('"'); break;
        case 'a': out.push_back('\a'); break;
        case 'b': out.push_back('\b'); break;
        case 'f': out.push_back('\f'); break;
        case 'n': out.push_back('\n'); break;
        case 'r': out.push_back('\r'); break;
        case 't': out.push_back('\t'); break;
        case 'v': out.push_back('\v'); break;
        case 'x': {
          if (i + 2 >= end || hexDigit(s[i + 1]) < 0 || hexDigit(s[i + 2]) < 0) {
            fail("invalid \\x escape in STRING argument");
          }
          out.push_back(static_cast<char>(hexDigit(s[i + 1]) * 16 + hexDigit(s[i + 2])));
          i += 2;
          break;
        }
        default:
          if (e >= '0' && e <= '7') {
            int v = e - '0';
            for (int k = 0; k < 2 && i + 1 < end && s[i + 1] >= '0' && s[i + 1] <= '7'; ++k) {
              v = v * 8 + (s[++i] - '0');
            }
            out.push_back(static_cast<char>(v & 0xff));
          } else {
            out.push_back('\\');
            out.push_back(e);
          }
      }
    }
    return out;
  }
  static void appendUtf8(std::string& out, std::uint32_t cp) {
    if (cp < 0x80) {
      out.push_back(static_cast<char>(cp));
    } else if (cp < 0x800) {
      out.push_back(static_cast<char>(0xc0 | (cp >> 6)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3f)));
    } else if (cp < 0x10000) {
      out.push_back(static_cast<char>(0xe0 | (cp >> 12)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3f)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3f)));
    } else {
      out.push_back(static_cast<char>(0xf0 | (cp >> 18)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3f)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3f)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3f)));
    }
  }
  // UNICODE's argument: raw-unicode-escape (latin-1 bytes plus \uXXXX / \UXXXXXXXX) to UTF-8.
  std::string rawUnicodeEscape(const std::string& s) {
    std::string out;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const unsigned char c = static_cast<unsigned char>(s[i]);
      if (c == '\\' && i + 1 < s.size() && (s[i + 1] == 'u' || s[i + 1] == 'U')) {
        const std::size_t digits = s[i + 1] == 'u' ? 4 : 8;
        if (i + 2 + digits > s.size()) fail("truncated \\u escape in UNICODE argument");
        std::uint32_t cp = 0;
        for (std::size_t k = 0; k < digits; ++k) {
          const int h = hexDigit(s[i + 2 + k]);
          if (h < 0) fail("invalid \\u escape in UNICODE argument");
          cp = cp * 16 + static_cast<std::uint32_t>(h);
        }
        if (cp > 0x10ffff) fail("code point beyond U+10FFFF in UNICODE argument");
        appendUtf8(out, cp);
        i += 1 + digits;
      } else {
        appendUtf8(out, c);
      }
    }
    return out;
  }
  // LONG1 / LONG4: little-endian two's complement of n bytes; must fit in 64 bits.
  std::int64_t binaryLong(std::uint64_t n) {
    need(n, "LONG argument");
    const std::uint8_t* p = data_ + pos_;
    pos_ += static_cast<std::size_t>(n);
    if (n == 0) return 0;
    const bool neg = (p[n - 1] & 0x80) != 0;
    const std::uint8_t ext = neg ? 0xff : 0x00;
    for (std::uint64_t i = 8; i < n; ++i) {
      if (p[i] != ext) fail("integer does not fit in 64 bits");
    }
    if (n > 8 && ((p[7] & 0x80) != 0) != neg) fail("integer does not fit in 64 bits");
    std::uint64_t v = neg ? ~std::uint64_t(0) : 0;
    const std::uint64_t m = n < 8 ? n : 8;
    for (std::uint64_t i = 0; i < m; ++i) {
      v &= ~(std::uint64_t(0xff) << (8 * i));
      v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
    }
    std::int64_t s;
    std::memcpy(&s, &v, 8);
    return s;
  }

  // --- record builders -----------------------------------------------------------------------
  std::uint32_t makeRecord(Kind k, std::uint32_t callable, std::uint32_t args,
                           std::uint32_t kwargs = detail::kNoIndex) {
    const std::uint32_t i = make(k);
    at(i).depth = 1;
    at(i).items.push_back(callable);
    at(i).items.push_back(args);
    cover(i, callable);
    cover(i, args);
    if (kwargs != detail::kNoIndex) {
      at(i).items.push_back(kwargs);
      cover(i, kwargs);
    }
    return i;
  }
  void appendTo(std::uint32_t target, const std::uint32_t* items, std::size_t n, Kind want,
                const char* opname) {
    if (at(target).kind != want) {
      fail(std::string(opname) + " on a " + kindName(at(target).kind) + " (only " +
           kindName(want) + " is supported)");
    }
    for (std::size_t j = 0; j < n; ++j) {
      at(target).items.push_back(items[j]);
      cover(target, items[j]);
    }
  }

  // --- one opcode; returns true at STOP --------------------------------------------------------
  bool step(std::uint8_t code) {
    switch (code) {
      // protocol 0 / 1
      case '(':  // MARK
        if (marks_.size() >= limits_.maxDepth) {
          fail("more than " + std::to_string(limits_.maxDepth) + " MARKs open (limit)");
        }
        marks_.push_back(stack_.size());
        return false;
      case '.': {  // STOP
        doc_.root_ = pop();
        return true;
      }
      case '0':  // POP: the top item, or the MARK when the segment above it is empty
        if (stack_.size() > base()) {
          stack_.pop_back();
        } else {
          popMark();
        }
        return false;
      case '1':  // POP_MARK
        popMark();
        return false;
      case '2':  // DUP
        push(top());
        return false;
      case 'F':  // FLOAT
      {
        const double v = textFloat(readLine("FLOAT"));
        const std::uint32_t i = make(Kind::Float);
        at(i).real = v;
        push(i);
        return false;
      }
      case 'I': {  // INT (I01 / I00 are True / False)
        const std::string s = readLine("INT");
        if (s == "01" || s == "00") {
          push(makeInt(Kind::Bool, s == "01" ? 1 : 0));
        } else {
          push(makeInt(Kind::Int, textInt(s, false)));
        }
        return false;
      }
      case 'J':  // BININT
        push(makeInt(Kind::Int, readI32("BININT")));
        return false;
      case 'K':  // BININT1
        push(makeInt(Kind::Int, static_cast<std::int64_t>(readLE(1, "BININT1"))));
        return false;
      case 'L':  // LONG
        push(makeInt(Kind::Int, textInt(readLine("LONG"), true)));
        return false;
      case 'M':  // BININT2
        push(makeInt(Kind::Int, static_cast<std::int64_t>(readLE(2, "BININT2"))));
        return false;
      case 'N':  // NONE
        push(make(Kind::None));
        return false;
      case 'P':  // PERSID
      case 'Q':  // BINPERSID
        fail("persistent IDs are not supported");
      case 'R': {  // REDUCE
        const std::uint32_t args = pop();
        const std::uint32_t callable = pop();
        push(makeRecord(Kind::Reduce, callable, args));
        return false;
      }
      case 'S':  // STRING (Python-2 str, quoted repr)
        push(makeString(Kind::Bytes, unquote(readLine("STRING"))));
        return false;
      case 'T': {  // BINSTRING
        const std::int32_t n = readI32("BINSTRING length");
        if (n < 0) fail("negative BINSTRING length");
        push(makeString(Kind::Bytes, readBytes(static_cast<std::uint64_t>(n), "BINSTRING")));
        return false;
      }
      case 'U':  // SHORT_BINSTRING
      {
        const std::uint64_t n = readLE(1, "SHORT_BINSTRING length");
        push(makeString(Kind::Bytes, readBytes(n, "SHORT_BINSTRING")));
        return false;
      }
      case 'V':  // UNICODE
        push(makeString(Kind::Str, rawUnicodeEscape(readLine("UNICODE"))));
        return false;
      case 'X': {  // BINUNICODE
        const std::uint64_t n = readLE(4, "BINUNICODE length");
        push(makeString(Kind::Str, readBytes(n, "BINUNICODE")));
        return false;
      }
      case 'a': {  // APPEND
        const std::uint32_t v = pop();
        appendTo(top(), &v, 1, Kind::List, "APPEND");
        return false;
      }
      case 'b': {  // BUILD: attach the state to the object record below it
        const std::uint32_t st = pop();
        const std::uint32_t obj = top();
        const Kind k = at(obj).kind;
        if (k != Kind::Reduce && k != Kind::NewObj) {
          fail(std::string("BUILD on a ") + kindName(k) + " (only object records take a state)");
        }
        at(obj).state = st;
        cover(obj, st);
        return false;
      }
      case 'c': {  // GLOBAL
        std::string module = readLine("GLOBAL module");
        std::string name = readLine("GLOBAL name");
        push(makeGlobal(std::move(module), std::move(name)));
        return false;
      }
      case 'd': {  // DICT
        const std::vector<std::uint32_t> items = popMark();
        if (items.size() % 2 != 0) fail("DICT with an odd number of items");
        push(makeContainer(Kind::Dict, items.data(), items.size()));
        return false;
      }
      case '}':  // EMPTY_DICT
        push(makeContainer(Kind::Dict, nullptr, 0));
        return false;
      case 'e': {  // APPENDS
        const std::vector<std::uint32_t> items = popMark();
        appendTo(top(), items.data(), items.size(), Kind::List, "APPENDS");
        return false;
      }
      case 'g':  // GET
        push(memoGet(textMemoKey(readLine("GET"))));
        return false;
      case 'h':  // BINGET
        push(memoGet(readLE(1, "BINGET")));
        return false;
      case 'j':  // LONG_BINGET
        push(memoGet(readLE(4, "LONG_BINGET")));
        return false;
      case 'i': {  // INST: class by name, arguments from the MARK
        std::string module = readLine("INST module");
        std::string name = readLine("INST name");
        const std::vector<std::uint32_t> args = popMark();
        const std::uint32_t cls = makeGlobal(std::move(module), std::move(name));
        const std::uint32_t tup = makeContainer(Kind::Tuple, args.data(), args.size());
        push(makeRecord(Kind::NewObj, cls, tup));
        return false;
      }
      case 'o': {  // OBJ: class and arguments from the MARK
        const std::vector<std::uint32_t> items = popMark();
        if (items.empty()) fail("OBJ without a class");
        const std::uint32_t tup = makeContainer(Kind::Tuple, items.data() + 1, items.size() - 1);
        push(makeRecord(Kind::NewObj, items[0], tup));
        return false;
      }
      case 'l': {  // LIST
        const std::vector<std::uint32_t> items = popMark();
        push(makeContainer(Kind::List, items.data(), items.size()));
        return false;
      }
      case ']':  // EMPTY_LIST
        push(makeContainer(Kind::List, nullptr, 0));
        return false;
      case 'p':  // PUT
        memoPut(textMemoKey(readLine("PUT")));
        return false;
      case 'q':  // BINPUT
        memoPut(readLE(1, "BINPUT"));
        return false;
      case 'r':  // LONG_BINPUT
        memoPut(readLE(4, "LONG_BINPUT"));
        return false;
      case 's': {  // SETITEM
        const std::uint32_t v = pop();
        const std::uint32_t k = pop();
        const std::uint32_t pair[2] = {k, v};
        appendTo(top(), pair, 2, Kind::Dict, "SETITEM");
        return false;
      }
      case 'u': {  // SETITEMS
        const std::vector<std::uint32_t> items = popMark();
        if (items.size() % 2 != 0) fail("SETITEMS with an odd number of items");
        appendTo(top(), items.data(), items.size(), Kind::Dict, "SETITEMS");
        return false;
      }
      case 't': {  // TUPLE
        const std::vector<std::uint32_t> items = popMark();
        push(makeContainer(Kind::Tuple, items.data(), items.size()));
        return false;
      }
      case ')':  // EMPTY_TUPLE
        push(makeContainer(Kind::Tuple, nullptr, 0));
        return false;
      case 'G': {  // BINFLOAT: big-endian IEEE-754 double
        need(8, "BINFLOAT");
        std::uint64_t u = 0;
        for (int k = 0; k < 8; ++k) u = (u << 8) | data_[pos_ + static_cast<std::size_t>(k)];
        pos_ += 8;
        double v;
        std::memcpy(&v, &u, 8);
        const std::uint32_t i = make(Kind::Float);
        at(i).real = v;
        push(i);
        return false;
      }
      // protocol 2
      case 0x80: {  // PROTO
        const std::uint64_t p = readLE(1, "PROTO");
        if (p > 5) fail("unsupported pickle protocol " + std::to_string(p));
        doc_.protocol_ = static_cast<int>(p);
        return false;
      }
      case 0x81: {  // NEWOBJ
        const std::uint32_t args = pop();
        const std::uint32_t cls = pop();
        push(makeRecord(Kind::NewObj, cls, args));
        return false;
      }
      case 0x82:
      case 0x83:
      case 0x84:  // EXT1 / EXT2 / EXT4
        fail("extension registry codes (EXT1/EXT2/EXT4) are not supported");
      case 0x85:
      case 0x86:
      case 0x87: {  // TUPLE1 / TUPLE2 / TUPLE3
        const std::size_t n = static_cast<std::size_t>(code - 0x84);
        std::uint32_t items[3] = {0, 0, 0};
        for (std::size_t k = n; k-- > 0;) items[k] = pop();
        push(makeContainer(Kind::Tuple, items, n));
        return false;
      }
      case 0x88:  // NEWTRUE
        push(makeInt(Kind::Bool, 1));
        return false;
      case 0x89:  // NEWFALSE
        push(makeInt(Kind::Bool, 0));
        return false;
      case 0x8a:  // LONG1
        push(makeInt(Kind::Int, binaryLong(readLE(1, "LONG1 length"))));
        return false;
      case 0x8b: {  // LONG4
        const std::int32_t n = readI32("LONG4 length");
        if (n < 0) fail("negative LONG4 length");
        push(makeInt(Kind::Int, binaryLong(static_cast<std::uint64_t>(n))));
        return false;
      }
      // protocol 3
      case 'B': {  // BINBYTES
        const std::uint64_t n = readLE(4, "BINBYTES length");
        push(makeString(Kind::Bytes, readBytes(n, "BINBYTES")));
        return false;
      }
      case 'C': {  // SHORT_BINBYTES
        const std::uint64_t n = readLE(1, "SHORT_BINBYTES length");
        push(makeString(Kind::Bytes, readBytes(n, "SHORT_BINBYTES")));
        return false;
      }
      // protocol 4
      case 0x8c: {  // SHORT_BINUNICODE
        const std::uint64_t n = readLE(1, "SHORT_BINUNICODE length");
        push(makeString(Kind::Str, readBytes(n, "SHORT_BINUNICODE")));
        return false;
      }
      case 0x8d: {  // BINUNICODE8
        const std::uint64_t n = readLE(8, "BINUNICODE8 length");
        push(makeString(Kind::Str, readBytes(n, "BINUNICODE8")));
        return false;
      }
      case 0x8e: {  // BINBYTES8
        const std::uint64_t n = readLE(8, "BINBYTES8 length");
        push(makeString(Kind::Bytes, readBytes(n, "BINBYTES8")));
        return false;
      }
      case 0x8f:  // EMPTY_SET
        push(makeContainer(Kind::Set, nullptr, 0));
        return false;
      case 0x90: {  // ADDITEMS
        const std::vector<std::uint32_t> items = popMark();
        appendTo(top(), items.data(), items.size(), Kind::Set, "ADDITEMS");
        return false;
      }
      case 0x91: {  // FROZENSET
        const std::vector<std::uint32_t> items = popMark();
        push(makeContainer(Kind::FrozenSet, items.data(), items.size()));
        return false;
      }
      case 0x92: {  // NEWOBJ_EX
        const std::uint32_t kwargs = pop();
        const std::uint32_t args = pop();
        const std::uint32_t cls = pop();
        push(makeRecord(Kind::NewObj, cls, args, kwargs));
        return false;
      }
      case 0x93: {  // STACK_GLOBAL
        const std::uint32_t name = pop();
        const std::uint32_t module = pop();
        if (at(name).kind != Kind::Str || at(module).kind != Kind::Str) {
          fail("STACK_GLOBAL needs two str values");
        }
        push(makeGlobal(doc_.strings_[at(module).text], doc_.strings_[at(name).text]));
        return false;
      }
      case 0x94:  // MEMOIZE
        memoPut(memo_.size());
        return false;
      case 0x95: {  // FRAME: only a read-ahead hint; its length must fit in the input
        const std::uint64_t n = readLE(8, "FRAME length");
        need(n, "FRAME");
        return false;
      }
      // protocol 5
      case 0x96: {  // BYTEARRAY8
        const std::uint64_t n = readLE(8, "BYTEARRAY8 length");
        push(makeString(Kind::Bytes, readBytes(n, "BYTEARRAY8")));
        return false;
      }
      case 0x97:  // NEXT_BUFFER
      case 0x98:  // READONLY_BUFFER
        fail("out-of-band buffers (NEXT_BUFFER / READONLY_BUFFER) are not supported");
      default: {
        static const char* hex = "0123456789abcdef";
        fail(std::string("unknown opcode 0x") + hex[code >> 4] + hex[code & 15]);
      }
    }
  }

  const std::uint8_t* data_;
  std::size_t size_;
  Limits limits_;
  std::size_t maxNodes_ = 0;
  std::size_t pos_ = 0;
  std::size_t op_ = 0;  // offset of the opcode being interpreted
  Document doc_;
  std::vector<std::uint32_t> stack_;
  std::vector<std::size_t> marks_;  // stack sizes at each open MARK
  std::unordered_map<std::uint64_t, std::uint32_t> memo_;
};

/// Parses one pickle from memory into an inert Document (nothing is imported or called).
inline Document parse(const std::uint8_t* data, std::size_t size, const Limits& limits = {}) {
  return Parser(data, size, limits).run();
}
inline Document parse(const std::string& bytes, const Limits& limits = {}) {
  return parse(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), limits);
}

}  // namespace pickle
}  // namespace hawor
