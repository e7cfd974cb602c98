// hawor/io/npy.hpp — numpy's .npy format: an N-d array type, parsing and writing.
//
// Format (numpy `lib/format.py`, NEP 1): magic "\x93NUMPY", major, minor version byte, then the
// header length (2 bytes little-endian in version 1.0, 4 bytes in 2.0 and 3.0), then a Python dict
// literal {'descr': <dtype str>, 'fortran_order': <bool>, 'shape': <tuple of int>} padded with
// spaces and ended by '\n', then the raw element bytes (C or Fortran order, byte order in descr).
//
// Supported dtypes: bool '|b1', signed and unsigned integers of 1, 2, 4, 8 bytes, float16, float32,
// float64, in either byte order. Object ('O'), string, complex, datetime and structured dtypes are
// rejected with hawor::Error (object arrays would need pickle). Every size in a header is checked
// against overflow and against the bytes actually present before anything is allocated.
// Thread-safety: all functions are reentrant; an NpyArray is a plain value.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../common.hpp"
#include "detail/bytes.hpp"
#include "file.hpp"

namespace hawor {

/// Element kinds of the dtypes this module reads and writes.
enum class NpyKind { Bool, Int, UInt, Float };

/// A parsed numpy scalar dtype: kind, item size in bytes and byte order.
struct NpyType {
  NpyKind kind = NpyKind::Float;
  size_t itemsize = 8;
  bool big_endian = false;

  /// Parses a numpy descr string such as "<f8", ">i4", "|u1", "|b1", "f4" (no order = native).
  /// Throws hawor::Error naming `what` for unsupported or malformed dtypes.
  static NpyType parse(const std::string& descr, const std::string& what) {
    const auto fail = [&](const std::string& why) -> Error {
      return Error(what + ": dtype '" + descr + "' " + why);
    };
    if (descr.empty()) throw fail("is empty");
    size_t i = 0;
    char order = '=';
    if (descr[0] == '<' || descr[0] == '>' || descr[0] == '|' || descr[0] == '=') {
      order = descr[0];
      i = 1;
    }
    if (i >= descr.size()) throw fail("has no type code");
    const char code = descr[i++];
    if (code == 'O') throw fail("is an object array (pickled Python objects): not supported");
    if (code == '?' && i == descr.size()) return NpyType{NpyKind::Bool, 1, false};
    size_t size = 0;
    const size_t digits_begin = i;
    for (; i < descr.size(); ++i) {
      const char c = descr[i];
      if (c < '0' || c > '9' || i - digits_begin >= 4) throw fail("is malformed");
      size = size * 10 + static_cast<size_t>(c - '0');
    }
    if (i == digits_begin) throw fail("has no item size");
    NpyType t;
    t.itemsize = size;
    switch (code) {
      case 'b':
        if (size != 1) throw fail("is not a supported boolean type");
        t.kind = NpyKind::Bool;
        break;
      case 'i':
      case 'u':
        if (size != 1 && size != 2 && size != 4 && size != 8) throw fail("has an unsupported size");
        t.kind = code == 'i' ? NpyKind::Int : NpyKind::UInt;
        break;
      case 'f':
        if (size != 2 && size != 4 && size != 8) {
          throw fail("is not supported (only float16, float32, float64)");
        }
        t.kind = NpyKind::Float;
        break;
      case 'c': throw fail("is complex: not supported");
      case 'S': case 'U': case 'a': throw fail("is a string type: not supported");
      case 'V': throw fail("is a void/structured type: not supported");
      case 'M': case 'm': throw fail("is a datetime type: not supported");
      default: throw fail("is not a recognised numpy type code");
    }
    if (size == 1) {
      t.big_endian = false;
    } else if (order == '|') {
      throw fail("has byte order '|' but a multi-byte item size");
    } else if (order == '=') {
      t.big_endian = !detail::hostIsLittleEndian();
    } else {
      t.big_endian = order == '>';
    }
    return t;
  }

  /// Canonical numpy descr: '|' for one-byte types, else '<' or '>' then code and size.
  std::string descr() const {
    std::string s;
    s += itemsize == 1 ? '|' : (big_endian ? '>' : '<');
    s += kind == NpyKind::Bool ? 'b' : kind == NpyKind::Int ? 'i' : kind == NpyKind::UInt ? 'u' : 'f';
    s += std::to_string(itemsize);
    return s;
  }

  /// Readable name for messages: "float64", "uint8", "bool", "int32 (big-endian)".
  std::string name() const {
    std::string s = kind == NpyKind::Bool ? "bool"
                    : kind == NpyKind::Int ? "int" + std::to_string(8 * itemsize)
                    : kind == NpyKind::UInt ? "uint" + std::to_string(8 * itemsize)
                                            : "float" + std::to_string(8 * itemsize);
    if (big_endian && itemsize > 1) s += " (big-endian)";
    return s;
  }
};

/// Maps a C++ element type to its numpy kind and size. Defined for bool, every integer type of
/// 1, 2, 4 or 8 bytes, float and double; any other type fails to compile.
template <typename T, typename Enable = void>
struct NpyTraits;

template <>
struct NpyTraits<bool> {
  static constexpr NpyKind kind = NpyKind::Bool;
  static constexpr size_t size = 1;
};

template <typename T>
struct NpyTraits<T, std::enable_if_t<std::is_integral<T>::value && !std::is_same<T, bool>::value>> {
  static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8,
                "unsupported integer size for .npy");
  static constexpr NpyKind kind = std::is_signed<T>::value ? NpyKind::Int : NpyKind::UInt;
  static constexpr size_t size = sizeof(T);
};

template <typename T>
struct NpyTraits<T, std::enable_if_t<std::is_floating_point<T>::value>> {
  static_assert(std::is_same<T, float>::value || std::is_same<T, double>::value,
                ".npy supports float and double (long double is not portable)");
  static constexpr NpyKind kind = NpyKind::Float;
  static constexpr size_t size = sizeof(T);
};

/// The little-endian numpy dtype of T: npyType<double>() is "<f8".
template <typename T>
NpyType npyType(bool big_endian = false) {
  return NpyType{NpyTraits<T>::kind, NpyTraits<T>::size, NpyTraits<T>::size > 1 && big_endian};
}

namespace detail {

/// IEEE 754 binary16 -> binary32 (exact: every half is a float). Handles subnormals, inf, NaN.
inline float halfToFloat(uint16_t h) {
  const uint32_t sign = static_cast<uint32_t>(h & 0x8000u) << 16;
  const uint32_t exp = (h >> 10) & 0x1Fu;
  uint32_t mant = h & 0x3FFu;
  uint32_t bits;
  if (exp == 0x1F) {
    bits = sign | 0x7F800000u | (mant << 13);  // inf or NaN (payload kept)
  } else if (exp != 0) {
    bits = sign | ((exp + 112u) << 23) | (mant << 13);  // rebias 15 -> 127
  } else if (mant == 0) {
    bits = sign;  // signed zero
  } else {
    // Subnormal half: value = mant * 2^-24; normalise into a float.
    uint32_t e = 113;  // 127 - 14
    while ((mant & 0x400u) == 0) {
      mant <<= 1;
      --e;
    }
    bits = sign | (e << 23) | ((mant & 0x3FFu) << 13);
  }
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

/// One element decoded to the widest C++ type of its kind.
struct NpyScalar {
  NpyKind kind;
  int64_t i = 0;   // NpyKind::Int
  uint64_t u = 0;  // NpyKind::UInt and NpyKind::Bool (0 or 1)
  double f = 0;    // NpyKind::Float

  std::string text() const {
    switch (kind) {
      case NpyKind::Bool: return u ? "True" : "False";
      case NpyKind::Int: return std::to_string(i);
      case NpyKind::UInt: return std::to_string(u);
      default: {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", f);
        return buf;
      }
    }
  }
};

inline NpyScalar decodeElement(const uint8_t* p, const NpyType& t) {
  const uint64_t raw = t.big_endian ? loadBE(p, t.itemsize) : loadLE(p, t.itemsize);
  NpyScalar s{t.kind};
  switch (t.kind) {
    case NpyKind::Bool: s.u = raw != 0; break;
    case NpyKind::UInt: s.u = raw; break;
    case NpyKind::Int: {
      uint64_t v = raw;
      const unsigned bits = static_cast<unsigned>(8 * t.itemsize);
      if (bits < 64 && ((v >> (bits - 1)) & 1u)) v |= ~((uint64_t(1) << bits) - 1);  // sign-extend
      std::memcpy(&s.i, &v, 8);
      break;
    }
    case NpyKind::Float:
      if (t.itemsize == 2) {
        s.f = halfToFloat(static_cast<uint16_t>(raw));
      } else if (t.itemsize == 4) {
        const uint32_t b = static_cast<uint32_t>(raw);
        float f;
        std::memcpy(&f, &b, 4);
        s.f = f;
      } else {
        std::memcpy(&s.f, &raw, 8);
      }
      break;
  }
  return s;
}

/// Converts a decoded element to T, throwing when the value does not survive: non-integral or
/// out-of-range values to integer types, values other than 0/1 to bool, finite doubles beyond
/// float's range to float. Integer -> floating conversions round to nearest (like numpy astype).
template <typename T>
T convertElement(const NpyScalar& s, const NpyType& from, size_t index, const std::string& what) {
  const auto fail = [&](const char* why) -> Error {
    return Error(what + ": element " + std::to_string(index) + " (" + s.text() + ") of " +
                 from.name() + " array " + why);
  };
  if constexpr (std::is_same<T, bool>::value) {
    if (s.kind == NpyKind::Bool) return s.u != 0;
    const bool zero = s.kind == NpyKind::Int ? s.i == 0 : s.kind == NpyKind::UInt ? s.u == 0 : s.f == 0;
    const bool one = s.kind == NpyKind::Int ? s.i == 1 : s.kind == NpyKind::UInt ? s.u == 1 : s.f == 1;
    if (!zero && !one) throw fail("is neither 0 nor 1: cannot convert to bool");
    return one;
  } else if constexpr (std::is_floating_point<T>::value) {
    switch (s.kind) {
      case NpyKind::Bool:
      case NpyKind::UInt: return static_cast<T>(s.u);
      case NpyKind::Int: return static_cast<T>(s.i);
      default:
        if (std::is_same<T, float>::value && std::isfinite(s.f) &&
            std::fabs(s.f) > static_cast<double>(std::numeric_limits<float>::max())) {
          throw fail("is outside the range of float32");
        }
        return static_cast<T>(s.f);
    }
  } else {
    static_assert(std::is_integral<T>::value, "as<T>: T must be bool, an integer or floating type");
    using L = std::numeric_limits<T>;
    switch (s.kind) {
      case NpyKind::Bool: return static_cast<T>(s.u);
      case NpyKind::UInt:
        if (s.u > static_cast<uint64_t>(L::max())) throw fail("is out of range for the requested type");
        return static_cast<T>(s.u);
      case NpyKind::Int:
        if constexpr (std::is_signed<T>::value) {
          if (s.i < static_cast<int64_t>(L::min()) || s.i > static_cast<int64_t>(L::max())) {
            throw fail("is out of range for the requested type");
          }
        } else {
          if (s.i < 0 || static_cast<uint64_t>(s.i) > static_cast<uint64_t>(L::max())) {
            throw fail("is out of range for the requested type");
          }
        }
        return static_cast<T>(s.i);
      default: {
        if (!std::isfinite(s.f)) throw fail("is not finite: cannot convert to an integer");
        if (s.f != std::trunc(s.f)) throw fail("is not an integer: cannot convert without loss");
        const int bits = static_cast<int>(8 * sizeof(T));
        // Exact bounds as doubles: [-2^(b-1), 2^(b-1)) signed, [0, 2^b) unsigned.
        const double lo = std::is_signed<T>::value ? -std::ldexp(1.0, bits - 1) : 0.0;
        const double hi = std::ldexp(1.0, std::is_signed<T>::value ? bits - 1 : bits);
        if (s.f < lo || s.f >= hi) throw fail("is out of range for the requested type");
        return static_cast<T>(s.f);
      }
    }
  }
}

/// Calls fn(c, s) for every element, c its C-order (row-major) index and s its index in storage
/// of the given order. Fortran order: strides 1, d0, d0*d1, ... walked with an odometer.
template <typename Fn>
void forEachElement(const std::vector<size_t>& shape, size_t count, bool fortran_order, Fn&& fn) {
  if (count == 0) return;
  if (!fortran_order || shape.size() <= 1) {
    for (size_t i = 0; i < count; ++i) fn(i, i);
    return;
  }
  const size_t nd = shape.size();
  std::vector<size_t> stride(nd), idx(nd, 0);
  stride[0] = 1;
  for (size_t k = 1; k < nd; ++k) stride[k] = stride[k - 1] * shape[k - 1];
  size_t s = 0;
  for (size_t c = 0; c < count; ++c) {
    fn(c, s);
    for (size_t k = nd; k-- > 0;) {
      if (++idx[k] < shape[k]) {
        s += stride[k];
        break;
      }
      s -= (shape[k] - 1) * stride[k];
      idx[k] = 0;
    }
  }
}

/// Product of the dimensions, or false on overflow of size_t.
inline bool shapeProduct(const std::vector<size_t>& shape, size_t* out) {
  uint64_t n = 1;
  for (size_t d : shape) {
    if (!checkedMul(n, d, &n)) return false;
  }
  if (!fitsSizeT(n)) return false;
  *out = static_cast<size_t>(n);
  return true;
}

}  // namespace detail

/// "(3, 4)", "(5,)", "()": the shape as numpy prints it.
inline std::string shapeString(const std::vector<size_t>& shape) {
  std::string s = "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i) s += ", ";
    s += std::to_string(shape[i]);
  }
  if (shape.size() == 1) s += ',';
  return s + ")";
}

/// An N-d numpy array held as its raw bytes: dtype descr, shape, memory order, element bytes.
/// Elements are decoded on demand by as<T>(), which also reorders Fortran data to C order.
struct NpyArray {
  std::string dtype = "<f8";       ///< numpy descr, e.g. "<f8", ">i4", "|u1", "|b1"
  std::vector<size_t> shape;       ///< empty = 0-d scalar
  bool fortran_order = false;      ///< true: column-major element bytes
  std::vector<uint8_t> bytes;      ///< size() * itemsize bytes

  size_t ndim() const { return shape.size(); }

  /// Number of elements (1 for a 0-d array). Throws if the product overflows.
  size_t size() const {
    size_t n = 0;
    if (!detail::shapeProduct(shape, &n)) throw Error("array shape " + shapeString(shape) + " overflows");
    return n;
  }

  /// The parsed dtype (throws for unsupported descr strings).
  NpyType type(const std::string& what = "array") const { return NpyType::parse(dtype, what); }

  /// Checks that the dtype is supported and bytes holds exactly size() elements.
  NpyType validate(const std::string& what = "array") const {
    const NpyType t = type(what);
    size_t n = 0;
    uint64_t nbytes = 0;
    if (!detail::shapeProduct(shape, &n) || !detail::checkedMul(n, t.itemsize, &nbytes) ||
        !detail::fitsSizeT(nbytes)) {
      throw Error(what + ": shape " + shapeString(shape) + " is too large");
    }
    if (bytes.size() != nbytes) {
      throw Error(what + ": holds " + std::to_string(bytes.size()) + " bytes but shape " +
                  shapeString(shape) + " of " + t.name() + " needs " + std::to_string(nbytes));
    }
    return t;
  }

  /// True when the stored kind and item size are exactly those of T (any byte order).
  template <typename T>
  bool is() const {
    NpyType t;
    try {
      t = type();
    } catch (const Error&) {
      return false;
    }
    return t.kind == NpyTraits<T>::kind && t.itemsize == NpyTraits<T>::size;
  }

  /// All elements converted to T in C (row-major) order. Conversions must preserve the value:
  /// float -> int requires integral in-range values, any -> bool requires 0/1, and so on (see
  /// detail::convertElement); otherwise hawor::Error names `what`, the element and its value.
  template <typename T>
  std::vector<T> as(const std::string& what = "array") const {
    const NpyType t = validate(what);
    const size_t n = size();
    std::vector<T> out(n);
    const bool c_layout = !fortran_order || shape.size() <= 1;
    if constexpr (!std::is_same<T, bool>::value) {
      // Same type, host byte order, C layout: a plain copy.
      if (c_layout && n > 0 && t.kind == NpyTraits<T>::kind && t.itemsize == sizeof(T) &&
          (t.itemsize == 1 || t.big_endian != detail::hostIsLittleEndian())) {
        std::memcpy(out.data(), bytes.data(), n * sizeof(T));
        return out;
      }
    }
    const uint8_t* base = bytes.data();
    detail::forEachElement(shape, n, fortran_order, [&](size_t c, size_t s) {
      out[c] = detail::convertElement<T>(detail::decodeElement(base + s * t.itemsize, t), t, c, what);
    });
    return out;
  }

  /// A 2-D array as a rows x cols matrix (a 1-D array as a column), converted as by as<T>().
  template <typename Scalar>
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> asMatrix(
      const std::string& what = "array") const {
    static_assert(!std::is_same<Scalar, bool>::value, "asMatrix: use as<bool>() for boolean arrays");
    if (shape.size() != 1 && shape.size() != 2) {
      throw Error(what + ": expected a 1-D or 2-D array, got shape " + shapeString(shape));
    }
    const size_t rows = shape[0], cols = shape.size() == 2 ? shape[1] : 1;
    const size_t max_index = static_cast<size_t>(std::numeric_limits<Eigen::Index>::max());
    if (rows > max_index || cols > max_index) throw Error(what + ": shape too large for a matrix");
    const std::vector<Scalar> v = as<Scalar>(what);
    Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(
        static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
    if (!v.empty()) std::memcpy(m.data(), v.data(), v.size() * sizeof(Scalar));
    return m;
  }

  /// An array of T's dtype from C-order values `data` (size = product of shape), stored in the
  /// requested memory order and byte order (numpy writes both; big-endian mainly for tests).
  template <typename T>
  static NpyArray fromData(const T* data, std::vector<size_t> shape, bool fortran_order = false,
                           bool big_endian = false) {
    NpyArray a;
    const NpyType t = npyType<T>(big_endian);
    a.dtype = t.descr();
    a.shape = std::move(shape);
    a.fortran_order = fortran_order;
    size_t n = 0;
    uint64_t nbytes = 0;
    if (!detail::shapeProduct(a.shape, &n) || !detail::checkedMul(n, t.itemsize, &nbytes) ||
        !detail::fitsSizeT(nbytes)) {
      throw Error("NpyArray::fromData: shape " + shapeString(a.shape) + " is too large");
    }
    a.bytes.resize(static_cast<size_t>(nbytes));
    uint8_t* base = a.bytes.data();
    detail::forEachElement(a.shape, n, fortran_order, [&](size_t c, size_t s) {
      uint64_t bits = 0;
      if constexpr (std::is_same<T, bool>::value) {
        bits = data[c] ? 1 : 0;
      } else if constexpr (sizeof(T) == 1) {
        uint8_t b;
        std::memcpy(&b, &data[c], 1);
        bits = b;
      } else if constexpr (sizeof(T) == 2) {
        uint16_t b;
        std::memcpy(&b, &data[c], 2);
        bits = b;
      } else if constexpr (sizeof(T) == 4) {
        uint32_t b;
        std::memcpy(&b, &data[c], 4);
        bits = b;
      } else {
        std::memcpy(&bits, &data[c], 8);
      }
      detail::storeBytes(base + s * t.itemsize, bits, t.itemsize, t.big_endian);
    });
    return a;
  }

  /// A 1-D array from a vector (std::vector<bool> included).
  template <typename T>
  static NpyArray fromVector(const std::vector<T>& v) {
    if constexpr (std::is_same<T, bool>::value) {
      std::vector<uint8_t> tmp(v.begin(), v.end());
      NpyArray a = fromData(tmp.data(), {v.size()});
      a.dtype = "|b1";
      return a;
    } else {
      return fromData(v.data(), {v.size()});
    }
  }

  /// A 2-D (rows, cols) C-order array from any Eigen matrix or array expression.
  template <typename Derived>
  static NpyArray fromEigen(const Eigen::DenseBase<Derived>& m) {
    using S = typename Derived::Scalar;
    const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = m;
    return fromData(rm.data(), {static_cast<size_t>(rm.rows()), static_cast<size_t>(rm.cols())});
  }

  /// An array from raw element bytes; validated (throws if dtype or byte count is wrong).
  static NpyArray fromRaw(std::string dtype, std::vector<size_t> shape, std::vector<uint8_t> bytes,
                          bool fortran_order = false) {
    NpyArray a;
    a.dtype = std::move(dtype);
    a.shape = std::move(shape);
    a.fortran_order = fortran_order;
    a.bytes = std::move(bytes);
    a.validate("NpyArray::fromRaw");
    return a;
  }

  bool operator==(const NpyArray& o) const {
    return dtype == o.dtype && shape == o.shape && fortran_order == o.fortran_order &&
           bytes == o.bytes;
  }
  bool operator!=(const NpyArray& o) const { return !(*this == o); }
};

namespace detail {

/// The subset of Python literals that numpy writes in .npy headers: str, int (with Python 2's
/// 'L'), True/False/None, tuples and lists (lists appear for structured dtypes, rejected later).
struct PyValue {
  enum class Kind { None, Str, Bool, Int, Tuple, List } kind = Kind::None;
  std::string str;
  bool boolean = false;
  bool negative = false;
  uint64_t integer = 0;
  std::vector<PyValue> items;
};

class PyLiteralParser {
 public:
  PyLiteralParser(const char* begin, const char* end, const std::string& what)
      : p_(begin), begin_(begin), end_(end), what_(what) {}

  /// The header: one dict with string keys, then only whitespace.
  std::vector<std::pair<std::string, PyValue>> parseDict() {
    std::vector<std::pair<std::string, PyValue>> out;
    skipWs();
    expect('{');
    skipWs();
    while (peek() != '}') {
      if (peek() != '\'' && peek() != '"') fail("expected a string key");
      std::string key = parseString();
      skipWs();
      expect(':');
      out.emplace_back(std::move(key), parseValue(0));
      skipWs();
      if (peek() == ',') {
        ++p_;
        skipWs();
      } else if (peek() != '}') {
        fail("expected ',' or '}'");
      }
    }
    ++p_;
    skipWs();
    if (p_ != end_) fail("unexpected text after the dict");
    return out;
  }

 private:
  static constexpr int kMaxDepth = 16;

  [[noreturn]] void fail(const std::string& why) const {
    throw Error(what_ + ": bad .npy header (" + why + " at offset " + std::to_string(p_ - begin_) +
                ") in \"" + printable(reinterpret_cast<const uint8_t*>(begin_),
                                      static_cast<size_t>(end_ - begin_), 120) + "\"");
  }
  char peek() const { return p_ < end_ ? *p_ : '\0'; }
  void expect(char c) {
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++p_;
  }
  void skipWs() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\n' || *p_ == '\r')) ++p_;
  }
  bool isIdent(char c) const {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (c >= '0' && c <= '9');
  }

  std::string parseString() {
    const char q = *p_++;
    std::string s;
    for (;;) {
      if (p_ >= end_ || *p_ == '\n') fail("unterminated string");
      const char c = *p_++;
      if (c == q) break;
      if (c == '\\') {
        if (p_ >= end_) fail("unterminated string");
        const char e = *p_++;
        if (e != '\\' && e != '\'' && e != '"') fail("unsupported escape in string");
        s += e;
      } else {
        s += c;
      }
    }
    return s;
  }

  PyValue parseValue(int depth) {
    if (depth > kMaxDepth) fail("nesting too deep");
    skipWs();
    PyValue v;
    const char c = peek();
    if (c == '\'' || c == '"') {
      v.kind = PyValue::Kind::Str;
      v.str = parseString();
    } else if ((c == 'u' || c == 'b') && p_ + 1 < end_ && (p_[1] == '\'' || p_[1] == '"')) {
      ++p_;  // u'...' / b'...' prefixes of Python 2/3 literals
      v.kind = PyValue::Kind::Str;
      v.str = parseString();
    } else if (c == '(' || c == '[') {
      const char close = c == '(' ? ')' : ']';
      v.kind = c == '(' ? PyValue::Kind::Tuple : PyValue::Kind::List;
      ++p_;
      skipWs();
      bool saw_comma = false;
      while (peek() != close) {
        v.items.push_back(parseValue(depth + 1));
        skipWs();
        if (peek() == ',') {
          ++p_;
          saw_comma = true;
          skipWs();
        } else if (peek() != close) {
          fail(std::string("expected ',' or '") + close + "'");
        }
      }
      ++p_;
      // "(3)" is the int 3 in Python, not a tuple.
      if (v.kind == PyValue::Kind::Tuple && v.items.size() == 1 && !saw_comma) return v.items[0];
    } else if (c == '-' || c == '+' || (c >= '0' && c <= '9')) {
      v.kind = PyValue::Kind::Int;
      if (c == '-' || c == '+') {
        v.negative = c == '-';
        ++p_;
      }
      if (!(peek() >= '0' && peek() <= '9')) fail("malformed integer");
      while (peek() >= '0' && peek() <= '9') {
        const uint64_t d = static_cast<uint64_t>(*p_ - '0');
        if (!checkedMul(v.integer, 10, &v.integer) || !checkedAdd(v.integer, d, &v.integer)) {
          fail("integer too large");
        }
        ++p_;
      }
      if (peek() == 'L' || peek() == 'l') ++p_;  // Python 2 long
      if (isIdent(peek()) || peek() == '.') fail("malformed integer");
    } else {
      const char* s = p_;
      while (p_ < end_ && isIdent(*p_)) ++p_;
      const std::string word(s, p_);
      if (word == "True" || word == "False") {
        v.kind = PyValue::Kind::Bool;
        v.boolean = word == "True";
      } else if (word == "None") {
        v.kind = PyValue::Kind::None;
      } else {
        p_ = s;
        fail("unexpected token");
      }
    }
    return v;
  }

  const char* p_;
  const char* begin_;
  const char* end_;
  const std::string& what_;
};

}  // namespace detail

/// Largest number of dimensions accepted (numpy 2 allows 64).
constexpr size_t kNpyMaxDims = 64;

/// Parses a complete .npy file held in memory. `what` (usually the file name) prefixes every
/// error. Rejects: bad magic or version, malformed or incomplete header dicts, unsupported
/// dtypes, shapes whose byte size overflows, and data shorter or longer than the shape needs.
inline NpyArray parseNpy(const uint8_t* data, size_t n, const std::string& what) {
  static const uint8_t kMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (n < 10 || (data == nullptr)) {
    throw Error(what + ": too short for a .npy file (" + std::to_string(n) + " bytes)");
  }
  if (std::memcmp(data, kMagic, 6) != 0) throw Error(what + ": not a .npy file (bad magic)");
  const unsigned major = data[6], minor = data[7];
  if (major < 1 || major > 3 || minor != 0) {
    throw Error(what + ": unsupported .npy version " + std::to_string(major) + "." +
                std::to_string(minor));
  }
  const size_t len_bytes = major == 1 ? 2 : 4;
  if (n < 8 + len_bytes) throw Error(what + ": truncated .npy header");
  const uint64_t header_len = detail::loadLE(data + 8, len_bytes);
  const uint64_t header_begin = 8 + len_bytes;
  if (header_len > n - header_begin) {
    throw Error(what + ": .npy header length " + std::to_string(header_len) +
                " exceeds the file size (truncated?)");
  }
  const char* h = reinterpret_cast<const char*>(data + header_begin);
  const size_t hl = static_cast<size_t>(header_len);
  if (hl == 0 || h[hl - 1] != '\n') {
    throw Error(what + ": .npy header does not end with a newline (truncated or corrupt)");
  }

  detail::PyLiteralParser parser(h, h + hl, what);
  const auto dict = parser.parseDict();
  const detail::PyValue* descr = nullptr;
  const detail::PyValue* fortran = nullptr;
  const detail::PyValue* shape = nullptr;
  for (const auto& kv : dict) {
    const detail::PyValue** slot = kv.first == "descr"           ? &descr
                                   : kv.first == "fortran_order" ? &fortran
                                   : kv.first == "shape"         ? &shape
                                                                 : nullptr;
    if (!slot) throw Error(what + ": .npy header has unexpected key '" + kv.first + "'");
    if (*slot) throw Error(what + ": .npy header repeats key '" + kv.first + "'");
    *slot = &kv.second;
  }
  if (!descr || !fortran || !shape) {
    throw Error(what + ": .npy header lacks '" +
                std::string(!descr ? "descr" : !fortran ? "fortran_order" : "shape") + "'");
  }
  using K = detail::PyValue::Kind;
  if (descr->kind == K::List) throw Error(what + ": structured dtypes are not supported");
  if (descr->kind != K::Str) throw Error(what + ": .npy header 'descr' is not a string");
  if (fortran->kind != K::Bool) throw Error(what + ": .npy header 'fortran_order' is not True/False");
  if (shape->kind != K::Tuple) throw Error(what + ": .npy header 'shape' is not a tuple");
  if (shape->items.size() > kNpyMaxDims) throw Error(what + ": .npy shape has too many dimensions");

  NpyArray a;
  const NpyType t = NpyType::parse(descr->str, what);
  a.dtype = descr->str;
  a.fortran_order = fortran->boolean;
  uint64_t count = 1;
  for (const auto& d : shape->items) {
    if (d.kind != K::Int) throw Error(what + ": .npy shape holds a non-integer");
    if (d.negative && d.integer != 0) throw Error(what + ": .npy shape has a negative dimension");
    if (!detail::fitsSizeT(d.integer) || !detail::checkedMul(count, d.integer, &count)) {
      throw Error(what + ": .npy shape is too large (element count overflows)");
    }
    a.shape.push_back(static_cast<size_t>(d.integer));
  }
  uint64_t nbytes = 0;
  if (!detail::checkedMul(count, t.itemsize, &nbytes) || !detail::fitsSizeT(nbytes)) {
    throw Error(what + ": .npy shape " + shapeString(a.shape) + " is too large");
  }
  const uint64_t available = n - header_begin - header_len;
  if (nbytes > available) {
    throw Error(what + ": .npy shape " + shapeString(a.shape) + " of " + t.name() + " needs " +
                std::to_string(nbytes) + " data bytes but only " + std::to_string(available) +
                " are present (truncated?)");
  }
  if (nbytes < available) {
    throw Error(what + ": .npy file has " + std::to_string(available - nbytes) +
                " trailing bytes after the array data");
  }
  const uint8_t* body = data + header_begin + header_len;
  a.bytes.assign(body, body + static_cast<size_t>(nbytes));
  return a;
}

inline NpyArray parseNpy(const std::vector<uint8_t>& bytes, const std::string& what) {
  return parseNpy(bytes.data(), bytes.size(), what);
}

/// Serialises an array as numpy does: version 1.0 (2.0 if the header needs more than 64 KiB),
/// header dict with sorted keys, padded with spaces so that the data starts at a multiple of 64.
inline std::vector<uint8_t> writeNpy(const NpyArray& a, const std::string& what = "array") {
  a.validate(what);
  std::string header = "{'descr': '" + a.dtype + "', 'fortran_order': " +
                       (a.fortran_order ? "True" : "False") + ", 'shape': " + shapeString(a.shape) +
                       ", }";
  size_t len_bytes = 2;
  unsigned major = 1;
  if (header.size() + 1 + 10 + 64 > 65535) {
    len_bytes = 4;
    major = 2;
  }
  const size_t prefix = 8 + len_bytes;
  const size_t unpadded = prefix + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::vector<uint8_t> out(prefix + header.size() + a.bytes.size());
  const uint8_t magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', static_cast<uint8_t>(major), 0};
  std::memcpy(out.data(), magic, 8);
  detail::storeBytes(out.data() + 8, header.size(), len_bytes, false);
  std::memcpy(out.data() + prefix, header.data(), header.size());
  if (!a.bytes.empty()) std::memcpy(out.data() + prefix + header.size(), a.bytes.data(), a.bytes.size());
  return out;
}

/// Reads a .npy file; errors name the path.
inline NpyArray readNpyFile(const std::string& path) {
  const std::vector<uint8_t> b = readFileBytes(path);
  return parseNpy(b.data(), b.size(), path);
}

/// Writes a .npy file; errors name the path.
inline void writeNpyFile(const std::string& path, const NpyArray& a) {
  writeFileBytes(path, writeNpy(a, path));
}

}  // namespace hawor
