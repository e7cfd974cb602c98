// hawor/hand/pickle_value.hpp — the inert value tree of the pickle reader (hand/pickle.hpp): node
// kinds, the parser's limits, and Value / Document, an arena of nodes that refer to each other by
// index (memo sharing and cycles without reference counting). Nothing here executes anything:
// globals are names, calls are records.
// Thread-safety: a Document is immutable after parsing; Values are views into it.
#pragma once

#include "hawor/common.hpp"

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

/// What a node is. Python-2 `str` (STRING / BINSTRING / SHORT_BINSTRING) and Python-3 `bytes`
/// are both Bytes; `unicode` / `str` (UNICODE / BINUNICODE...) is Str, stored as UTF-8.
enum class Kind : std::uint8_t {
  None,
  Bool,
  Int,
  Float,
  Str,
  Bytes,
  Tuple,
  List,
  Dict,
  Set,
  FrozenSet,
  Global,  ///< a name `module.name` (GLOBAL, STACK_GLOBAL, INST's class)
  Reduce,  ///< callable(*args) as a record: items = {callable, args}; optional BUILD state
  NewObj   ///< cls.__new__(cls, *args, **kwargs) (NEWOBJ, NEWOBJ_EX, OBJ, INST): items = {cls,
           ///< args[, kwargs]}; optional BUILD state
};

inline const char* kindName(Kind k) {
  switch (k) {
    case Kind::None: return "None";
    case Kind::Bool: return "bool";
    case Kind::Int: return "int";
    case Kind::Float: return "float";
    case Kind::Str: return "str";
    case Kind::Bytes: return "bytes";
    case Kind::Tuple: return "tuple";
    case Kind::List: return "list";
    case Kind::Dict: return "dict";
    case Kind::Set: return "set";
    case Kind::FrozenSet: return "frozenset";
    case Kind::Global: return "global";
    case Kind::Reduce: return "reduce";
    case Kind::NewObj: return "object";
  }
  return "?";
}

/// Resource limits of one parse.
struct Limits {
  /// Deepest nesting of containers / records, and most MARKs open at once.
  std::size_t maxDepth = 256;
  /// Most nodes the document may hold; 0 means `input size + 16` (each opcode creates at most one).
  std::size_t maxNodes = 0;
};

namespace detail {
constexpr std::uint32_t kNoIndex = 0xffffffffu;

struct Node {
  Kind kind = Kind::None;
  std::uint32_t depth = 0;         // 0 for scalars, 1 + deepest child for containers
  std::uint32_t text = kNoIndex;   // Str / Bytes: string index; Global: module
  std::uint32_t name = kNoIndex;   // Global: name
  std::uint32_t state = kNoIndex;  // Reduce / NewObj: BUILD state node
  std::int64_t integer = 0;        // Int, Bool (0 / 1)
  double real = 0.0;               // Float
  std::vector<std::uint32_t> items;  // containers; Dict: k0, v0, k1, v1, ...; records: see Kind
  std::size_t offset = 0;          // byte offset of the opcode that created the node
};
}  // namespace detail

class Document;

/// A read-only handle on one node of a Document (cheap to copy; valid while the Document lives).
/// Accessors throw hawor::Error when the node is not of the kind asked for.
class Value {
 public:
  Value() = default;
  Value(const Document* doc, std::uint32_t index) : doc_(doc), index_(index) {}

  Kind kind() const { return node().kind; }
  bool is(Kind k) const { return node().kind == k; }
  bool isNone() const { return is(Kind::None); }
  bool isString() const { return is(Kind::Str) || is(Kind::Bytes); }
  /// Byte offset in the input of the opcode that created this value (for error messages).
  std::size_t offset() const { return node().offset; }
  std::uint32_t index() const { return index_; }
  const Document* document() const { return doc_; }

  /// Int or Bool value.
  std::int64_t asInt() const {
    if (!is(Kind::Int) && !is(Kind::Bool)) wrongKind("an int");
    return node().integer;
  }
  bool asBool() const {
    if (!is(Kind::Int) && !is(Kind::Bool)) wrongKind("a bool");
    return node().integer != 0;
  }
  /// Float, Int or Bool value as double.
  double asFloat() const {
    if (is(Kind::Float)) return node().real;
    if (is(Kind::Int) || is(Kind::Bool)) return static_cast<double>(node().integer);
    wrongKind("a number");
  }
  /// Str (UTF-8) or Bytes content.
  const std::string& asString() const;
  /// Global module and name.
  const std::string& module() const;
  const std::string& name() const;
  /// "module.name" of a Global.
  std::string qualifiedName() const { return module() + "." + name(); }

  /// Element count of Tuple / List / Set / FrozenSet, or entry count of a Dict.
  std::size_t size() const {
    const detail::Node& n = node();
    switch (n.kind) {
      case Kind::Tuple:
      case Kind::List:
      case Kind::Set:
      case Kind::FrozenSet: return n.items.size();
      case Kind::Dict: return n.items.size() / 2;
      default: wrongKind("a container");
    }
  }
  /// i-th element of a Tuple / List / Set / FrozenSet.
  Value operator[](std::size_t i) const {
    const detail::Node& n = node();
    if (!(is(Kind::Tuple) || is(Kind::List) || is(Kind::Set) || is(Kind::FrozenSet)))
      wrongKind("a sequence");
    if (i >= n.items.size()) outOfRange(i, n.items.size());
    return Value(doc_, n.items[i]);
  }
  /// i-th key / value of a Dict, in insertion order (duplicates kept; see find()).
  Value dictKey(std::size_t i) const { return dictEntry(i, 0); }
  Value dictValue(std::size_t i) const { return dictEntry(i, 1); }
  /// Dict lookup by a string key (matches Str and Bytes keys). The last matching entry wins,
  /// as it would in Python. Returns false when absent.
  bool find(const std::string& key, Value& out) const {
    const detail::Node& n = node();
    if (!is(Kind::Dict)) wrongKind("a dict");
    for (std::size_t i = n.items.size(); i >= 2; i -= 2) {
      const Value k(doc_, n.items[i - 2]);
      if (k.isString() && k.asString() == key) {
        out = Value(doc_, n.items[i - 1]);
        return true;
      }
    }
    return false;
  }
  bool has(const std::string& key) const {
    Value v;
    return find(key, v);
  }
  /// Dict lookup that throws (naming the key) when absent.
  Value at(const std::string& key) const;

  /// Reduce: the callable; NewObj: the class.
  Value callable() const {
    if (!is(Kind::Reduce) && !is(Kind::NewObj)) wrongKind("a reduce/object record");
    return Value(doc_, node().items[0]);
  }
  /// Reduce / NewObj: the positional argument tuple (or whatever the pickle pushed).
  Value args() const {
    if (!is(Kind::Reduce) && !is(Kind::NewObj)) wrongKind("a reduce/object record");
    return Value(doc_, node().items[1]);
  }
  /// BUILD state attached to a Reduce / NewObj record.
  bool hasState() const {
    return (is(Kind::Reduce) || is(Kind::NewObj)) && node().state != detail::kNoIndex;
  }
  Value state() const {
    if (!hasState()) wrongKind("an object with a BUILD state");
    return Value(doc_, node().state);
  }

  /// A one-line description for error messages, e.g. "call of os.system", "dict",
  /// "object of chumpy.ch.Ch" (looks at most one level deep: safe on cyclic documents).
  std::string describe() const;

 private:
  const detail::Node& node() const;
  Value dictEntry(std::size_t i, int which) const {
    const detail::Node& n = node();
    if (!is(Kind::Dict)) wrongKind("a dict");
    if (2 * i + 1 >= n.items.size()) outOfRange(i, n.items.size() / 2);
    return Value(doc_, n.items[2 * i + static_cast<std::size_t>(which)]);
  }
  [[noreturn]] void wrongKind(const char* expected) const;
  [[noreturn]] void outOfRange(std::size_t i, std::size_t n) const {
    throw Error("pickle: index " + std::to_string(i) + " out of range (size " + std::to_string(n) +
                ") for the value at byte offset " + std::to_string(offset()));
  }

  const Document* doc_ = nullptr;
  std::uint32_t index_ = 0;
};

/// The inert result of parsing one pickle: an arena of nodes and the root value.
class Document {
 public:
  Value root() const { return Value(this, root_); }
  std::size_t nodeCount() const { return nodes_.size(); }
  /// Protocol from the PROTO opcode (0 when absent, i.e. protocol 0 or 1).
  int protocol() const { return protocol_; }
  /// Offset just past STOP (trailing bytes, if any, are ignored as Python does).
  std::size_t endOffset() const { return end_; }

 private:
  friend class Value;
  friend class Parser;
  std::vector<detail::Node> nodes_;
  std::vector<std::string> strings_;
  std::uint32_t root_ = 0;
  int protocol_ = 0;
  std::size_t end_ = 0;
};

inline const detail::Node& Value::node() const {
  if (doc_ == nullptr || index_ >= doc_->nodes_.size()) throw Error("pickle: invalid value handle");
  return doc_->nodes_[index_];
}

inline const std::string& Value::asString() const {
  if (!isString()) wrongKind("a string");
  return doc_->strings_[node().text];
}

inline const std::string& Value::module() const {
  if (!is(Kind::Global)) wrongKind("a global");
  return doc_->strings_[node().text];
}

inline const std::string& Value::name() const {
  if (!is(Kind::Global)) wrongKind("a global");
  return doc_->strings_[node().name];
}

inline Value Value::at(const std::string& key) const {
  Value v;
  if (!find(key, v)) {
    throw Error("pickle: key '" + key + "' missing from the dict at byte offset " +
                std::to_string(offset()));
  }
  return v;
}

inline std::string Value::describe() const {
  const detail::Node& n = node();
  switch (n.kind) {
    case Kind::Global: return "global " + qualifiedName();
    case Kind::Reduce:
    case Kind::NewObj: {
      const Value c = callable();
      const std::string what = n.kind == Kind::Reduce ? "call of " : "object of ";
      if (c.is(Kind::Global)) return what + c.qualifiedName();
      return what + "a " + kindName(c.kind());
    }
    default: return kindName(n.kind);
  }
}

inline void Value::wrongKind(const char* expected) const {
  throw Error("pickle: expected " + std::string(expected) + ", got " + describe() +
              " at byte offset " + std::to_string(offset()));
}

}  // namespace pickle
}  // namespace hawor
