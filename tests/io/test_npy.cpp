// .npy: round trips of every dtype in both memory orders and byte orders, layout checks written
// from the format definition, value-checked conversions, and malformed input of every kind.
#include <catch2/catch.hpp>

#include <hawor/io/npy.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "io_test_util.hpp"

using hawor::NpyArray;
using io_test::errorOf;

// Every member template used here, instantiated explicitly so that all of them compile.
template std::vector<bool> NpyArray::as<bool>(const std::string&) const;
template std::vector<int8_t> NpyArray::as<int8_t>(const std::string&) const;
template std::vector<uint16_t> NpyArray::as<uint16_t>(const std::string&) const;
template std::vector<int64_t> NpyArray::as<int64_t>(const std::string&) const;
template std::vector<uint64_t> NpyArray::as<uint64_t>(const std::string&) const;
template std::vector<float> NpyArray::as<float>(const std::string&) const;
template std::vector<double> NpyArray::as<double>(const std::string&) const;
template NpyArray NpyArray::fromData<float>(const float*, std::vector<size_t>, bool, bool);
template NpyArray NpyArray::fromData<double>(const double*, std::vector<size_t>, bool, bool);
template Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>
NpyArray::asMatrix<float>(const std::string&) const;
template Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>
NpyArray::asMatrix<double>(const std::string&) const;

namespace {

// Sample values of T including its extremes (and, for floats, signed zero, infinities, NaN,
// subnormals).
template <typename T>
std::vector<T> sampleValues(size_t n, std::mt19937& rng) {
  std::vector<T> v(n);
  for (size_t i = 0; i < n; ++i) {
    if constexpr (std::is_same<T, bool>::value) {
      v[i] = (rng() & 1u) != 0;
    } else if constexpr (std::is_floating_point<T>::value) {
      std::normal_distribution<double> g(0.0, 100.0);
      v[i] = static_cast<T>(g(rng));
    } else {
      uint64_t r = (static_cast<uint64_t>(rng()) << 32) ^ rng();
      T t;
      std::memcpy(&t, &r, sizeof(T));
      v[i] = t;
    }
  }
  std::vector<T> specials;
  if constexpr (std::is_floating_point<T>::value) {
    using L = std::numeric_limits<T>;
    specials = {T(0), -T(0), L::infinity(), -L::infinity(), L::quiet_NaN(), L::denorm_min(),
                L::max(), L::lowest(), L::min()};
  } else if constexpr (!std::is_same<T, bool>::value) {
    using L = std::numeric_limits<T>;
    specials = {L::min(), L::max(), T(0), T(1)};
  }
  for (size_t i = 0; i < specials.size() && i < n; ++i) v[i] = specials[i];
  return v;
}

template <typename T>
uint64_t bitsOf(T v) {
  uint64_t b = 0;
  if constexpr (std::is_same<T, bool>::value) {
    b = v ? 1 : 0;
  } else {
    std::memcpy(&b, &v, sizeof(T));
  }
  return b;
}

// C index of a multi-index and Fortran offset of the same element, from the definitions:
// C: last index fastest; Fortran: first index fastest.
size_t fortranOffsetOfC(size_t c, const std::vector<size_t>& shape) {
  std::vector<size_t> idx(shape.size());
  for (size_t k = shape.size(); k-- > 0;) {
    idx[k] = c % shape[k];
    c /= shape[k];
  }
  size_t off = 0, stride = 1;
  for (size_t k = 0; k < shape.size(); ++k) {
    off += idx[k] * stride;
    stride *= shape[k];
  }
  return off;
}

// A .npy file with an arbitrary header text, version and body, laid out per the format.
std::vector<uint8_t> makeNpy(const std::string& dict, const std::vector<uint8_t>& body,
                             int major = 1, bool newline = true) {
  std::string h = dict;
  const size_t prefix = major == 1 ? 10 : 12;
  if (newline) {
    while ((prefix + h.size() + 1) % 64 != 0) h += ' ';
    h += '\n';
  }
  std::vector<uint8_t> out = {0x93, 'N', 'U', 'M', 'P', 'Y', static_cast<uint8_t>(major), 0};
  io_test::putLE(out, h.size(), major == 1 ? 2 : 4);
  out.insert(out.end(), h.begin(), h.end());
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

std::vector<uint8_t> f8Body(const std::vector<double>& v) {
  std::vector<uint8_t> b;
  for (double d : v) {
    uint64_t u;
    std::memcpy(&u, &d, 8);
    io_test::putLE(b, u, 8);
  }
  return b;
}

std::string npyError(const std::vector<uint8_t>& bytes) {
  return errorOf([&] { hawor::parseNpy(bytes.data(), bytes.size(), "test.npy"); });
}

}  // namespace

TEMPLATE_TEST_CASE("npy round trip of every dtype, C/Fortran order, both byte orders", "[io][npy]",
                   bool, int8_t, int16_t, int32_t, int64_t, uint8_t, uint16_t, uint32_t, uint64_t,
                   float, double) {
  using T = TestType;
  std::mt19937 rng(1234);
  const std::vector<std::vector<size_t>> shapes = {{}, {0}, {7}, {2, 3}, {2, 3, 4}, {3, 0, 2},
                                                   {1, 1, 1, 1}, {4, 1, 3, 2}};
  for (const auto& shape : shapes) {
    size_t n = 1;
    for (size_t d : shape) n *= d;
    // std::vector<bool> has no data(): keep the sample in a plain array.
    const std::vector<T> values = sampleValues<T>(n, rng);
    std::unique_ptr<T[]> raw(new T[n ? n : 1]);
    for (size_t i = 0; i < n; ++i) raw[i] = values[i];
    for (bool fortran : {false, true}) {
      for (bool big : {false, true}) {
        CAPTURE(hawor::shapeString(shape), fortran, big);
        const NpyArray a = NpyArray::fromData(raw.get(), shape, fortran, big);
        const hawor::NpyType t = hawor::npyType<T>(big);
        CHECK(a.dtype == t.descr());
        CHECK(a.bytes.size() == n * sizeof(T));
        REQUIRE(a.is<T>());

        // Layout: element c sits at the Fortran (or C) offset, bytes in the declared order.
        for (size_t c = 0; c < n; ++c) {
          const size_t s = fortran ? fortranOffsetOfC(c, shape) : c;
          const uint8_t* p = a.bytes.data() + s * sizeof(T);
          uint64_t stored = 0;
          for (size_t k = 0; k < sizeof(T); ++k) {
            const size_t byte = (big && sizeof(T) > 1) ? sizeof(T) - 1 - k : k;
            stored |= static_cast<uint64_t>(p[byte]) << (8 * k);
          }
          REQUIRE(stored == bitsOf<T>(values[c]));
        }

        const std::vector<uint8_t> file = hawor::writeNpy(a);
        const NpyArray b = hawor::parseNpy(file.data(), file.size(), "roundtrip.npy");
        REQUIRE(b == a);
        const std::vector<T> back = b.as<T>();
        REQUIRE(back.size() == n);
        for (size_t i = 0; i < n; ++i) REQUIRE(bitsOf<T>(back[i]) == bitsOf<T>(values[i]));
      }
    }
  }
}

TEST_CASE("npy header is written as numpy writes it", "[io][npy]") {
  const double v[6] = {1, 2, 3, 4, 5, 6};
  struct Case {
    std::vector<size_t> shape;
    bool fortran;
    std::string dict;
  };
  const std::vector<Case> cases = {
      {{2, 3}, false, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"},
      {{6}, false, "{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }"},
      {{}, false, "{'descr': '<f8', 'fortran_order': False, 'shape': (), }"},
      {{3, 2}, true, "{'descr': '<f8', 'fortran_order': True, 'shape': (3, 2), }"},
  };
  for (const auto& c : cases) {
    const size_t n = c.shape.empty() ? 1 : 6;
    const auto file = hawor::writeNpy(NpyArray::fromData(v, c.shape, c.fortran));
    const uint8_t magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
    REQUIRE(std::memcmp(file.data(), magic, 8) == 0);
    const size_t hl = io_test::getLE(file, 8, 2);
    CHECK((10 + hl) % 64 == 0);  // data aligned to 64 bytes
    const std::string header(file.begin() + 10, file.begin() + 10 + hl);
    CHECK(header.substr(0, c.dict.size()) == c.dict);
    CHECK(header.back() == '\n');
    CHECK(header.find_first_not_of(' ', c.dict.size()) == hl - 1);
    CHECK(file.size() == 10 + hl + n * 8);
  }
}

TEST_CASE("npy reads versions 1.0, 2.0, 3.0 and header variants", "[io][npy]") {
  const auto body = f8Body({1.5, -2, 3});
  const std::vector<std::string> dicts = {
      "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
      "{'descr': '<f8', 'fortran_order': False, 'shape': (3L,), }",  // Python 2 long
      "{\"descr\": \"<f8\", \"fortran_order\": False, \"shape\": (3,)}",
      "{ 'shape' : ( 3 , ) , 'fortran_order' : False , 'descr' : '<f8' }",
      "{'descr': u'<f8', 'fortran_order': False, 'shape': (3,)}",
  };
  for (int major : {1, 2, 3}) {
    for (const auto& d : dicts) {
      CAPTURE(major, d);
      const NpyArray a = hawor::parseNpy(makeNpy(d, body, major), "v.npy");
      REQUIRE(a.shape == std::vector<size_t>{3});
      REQUIRE(a.as<double>() == std::vector<double>{1.5, -2, 3});
    }
  }
  // Native and explicit byte order spellings of little-endian data on this (little-endian) host.
  if (hawor::detail::hostIsLittleEndian()) {
    for (const char* descr : {"f8", "=f8"}) {
      const std::string d = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (3,), }";
      REQUIRE(hawor::parseNpy(makeNpy(d, body), "v.npy").as<double>() == std::vector<double>{1.5, -2, 3});
    }
  }
  // 0-d array and one-byte types with any order character.
  const auto zero_d = makeNpy("{'descr': '<f8', 'fortran_order': False, 'shape': (), }", f8Body({7}));
  REQUIRE(hawor::parseNpy(zero_d, "z.npy").as<double>() == std::vector<double>{7});
  const auto u1 = makeNpy("{'descr': '<u1', 'fortran_order': False, 'shape': (2,), }", {200, 3});
  REQUIRE(hawor::parseNpy(u1, "u.npy").as<int>() == std::vector<int>{200, 3});
}

TEST_CASE("npy float16 decoding", "[io][npy]") {
  const std::vector<uint16_t> halves = {0x3C00, 0xC000, 0x7BFF, 0x0001, 0x0400, 0x7C00,
                                        0xFC00, 0x8000, 0x3555, 0x03FF};
  const std::vector<double> expect = {1.0,
                                      -2.0,
                                      65504.0,
                                      std::ldexp(1.0, -24),
                                      std::ldexp(1.0, -14),
                                      std::numeric_limits<double>::infinity(),
                                      -std::numeric_limits<double>::infinity(),
                                      -0.0,
                                      1365.0 / 4096.0,
                                      std::ldexp(1023.0, -24)};
  for (bool big : {false, true}) {
    std::vector<uint8_t> bytes;
    for (uint16_t h : halves) {
      if (big) {
        bytes.push_back(static_cast<uint8_t>(h >> 8));
        bytes.push_back(static_cast<uint8_t>(h));
      } else {
        io_test::putLE(bytes, h, 2);
      }
    }
    const NpyArray a = NpyArray::fromRaw(big ? ">f2" : "<f2", {halves.size()}, bytes);
    const auto d = a.as<double>();
    const auto f = a.as<float>();
    for (size_t i = 0; i < halves.size(); ++i) {
      CAPTURE(i, big);
      CHECK(d[i] == expect[i]);
      CHECK(std::signbit(d[i]) == std::signbit(expect[i]));
      CHECK(static_cast<double>(f[i]) == expect[i]);
    }
  }
  const NpyArray nan = NpyArray::fromRaw("<f2", {1}, {0x00, 0x7E});
  CHECK(std::isnan(nan.as<double>()[0]));
  const NpyArray ints = NpyArray::fromRaw("<f2", {2}, {0x00, 0x3C, 0x00, 0xC0});
  CHECK(ints.as<int>() == std::vector<int>{1, -2});
}

TEST_CASE("npy value-checked conversions", "[io][npy]") {
  const std::vector<int64_t> i8 = {1, -5, (int64_t(1) << 40)};
  const NpyArray ai = NpyArray::fromData(i8.data(), {3});
  CHECK(ai.as<double>() == std::vector<double>{1, -5, std::ldexp(1.0, 40)});
  CHECK(ai.as<int64_t>() == i8);
  CHECK_THAT(errorOf([&] { ai.as<int32_t>("big.npy"); }),
             Catch::Contains("big.npy") && Catch::Contains("element 2") && Catch::Contains("out of range"));
  CHECK_THAT(errorOf([&] { ai.as<uint64_t>(); }), Catch::Contains("element 1"));
  CHECK_THAT(errorOf([&] { ai.as<bool>(); }), Catch::Contains("neither 0 nor 1"));

  const std::vector<double> f = {1.0, 2.5};
  const NpyArray af = NpyArray::fromData(f.data(), {2});
  CHECK_THAT(errorOf([&] { af.as<int>("x"); }), Catch::Contains("element 1") && Catch::Contains("not an integer"));
  const double edge[3] = {255.0, -0.0, 0.0};
  CHECK(NpyArray::fromData(edge, {3}).as<uint8_t>() == std::vector<uint8_t>{255, 0, 0});
  for (double bad : {256.0, -1.0, 1e10, std::nan(""), HUGE_VAL}) {
    CAPTURE(bad);
    CHECK(io_test::outcome([&] { NpyArray::fromData(&bad, {1}).as<uint8_t>(); }) == 1);
  }
  // Exact integer bounds: 2^63 is out of int64 range, -2^63 is in.
  const double lo = -std::ldexp(1.0, 63), hi = std::ldexp(1.0, 63);
  CHECK(NpyArray::fromData(&lo, {1}).as<int64_t>()[0] == std::numeric_limits<int64_t>::min());
  CHECK(io_test::outcome([&] { NpyArray::fromData(&hi, {1}).as<int64_t>(); }) == 1);
  CHECK(NpyArray::fromData(&hi, {1}).as<uint64_t>()[0] == (uint64_t(1) << 63));

  const uint64_t umax = std::numeric_limits<uint64_t>::max();
  const NpyArray au = NpyArray::fromData(&umax, {1});
  CHECK(au.as<uint64_t>()[0] == umax);
  CHECK(au.as<double>()[0] == std::ldexp(1.0, 64));
  CHECK(io_test::outcome([&] { au.as<int64_t>(); }) == 1);
  const int32_t minus1 = -1;
  CHECK(io_test::outcome([&] { NpyArray::fromData(&minus1, {1}).as<uint32_t>(); }) == 1);

  const double huge = 1e300, inf = HUGE_VAL;
  CHECK_THAT(errorOf([&] { NpyArray::fromData(&huge, {1}).as<float>(); }), Catch::Contains("float32"));
  CHECK(std::isinf(NpyArray::fromData(&inf, {1}).as<float>()[0]));

  // bool <-> numbers: 0/1 only towards bool; any nonzero byte of a bool array is True.
  const std::vector<int> zo = {0, 1, 1};
  const auto bools = NpyArray::fromData(zo.data(), {3}).as<bool>();
  CHECK((bools == std::vector<bool>{false, true, true}));
  const NpyArray b = NpyArray::fromRaw("|b1", {3}, {0, 1, 2});
  CHECK((b.as<bool>() == std::vector<bool>{false, true, true}));
  CHECK(b.as<int>() == std::vector<int>{0, 1, 1});
  CHECK(b.as<double>() == std::vector<double>{0, 1, 1});
  CHECK(b.is<bool>());
  CHECK(!b.is<uint8_t>());
}

TEST_CASE("npy Eigen helpers", "[io][npy]") {
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  const NpyArray a = NpyArray::fromEigen(m);
  CHECK(a.shape == std::vector<size_t>{2, 3});
  CHECK(a.as<double>() == std::vector<double>{1, 2, 3, 4, 5, 6});  // C order
  CHECK(a.asMatrix<double>() == m);
  CHECK(a.asMatrix<float>() == m.cast<float>());
  // Fortran-ordered storage reads back as the same matrix.
  const double colmajor[6] = {1, 2, 3, 4, 5, 6};  // C-order values of shape (2, 3)
  const NpyArray f = NpyArray::fromData(colmajor, {2, 3}, true);
  CHECK(f.asMatrix<double>() == m);
  const std::vector<float> v = {1, 2, 3};
  const auto col = NpyArray::fromVector(v).asMatrix<float>();
  CHECK(col.rows() == 3);
  CHECK(col.cols() == 1);
  const std::vector<bool> vb = {true, false};
  CHECK(NpyArray::fromVector(vb).dtype == "|b1");
  const double x3[1] = {0};
  CHECK_THAT(errorOf([&] { NpyArray::fromData(x3, {1, 1, 1}).asMatrix<double>("t"); }),
             Catch::Contains("1-D or 2-D"));
}

TEST_CASE("npy rejects malformed files with hawor::Error", "[io][npy]") {
  const auto body = f8Body({1, 2, 3, 4, 5, 6});
  const auto ok = [&](const std::string& d) { return makeNpy(d, body); };
  REQUIRE(npyError(ok("{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }")) == "<no error>");

  struct Bad {
    std::string dict;
    std::string expect;
  };
  const std::vector<Bad> bad = {
      {"{'descr': '<f8', 'fortran_order': False}", "lacks 'shape'"},
      {"{'fortran_order': False, 'shape': (6,)}", "lacks 'descr'"},
      {"{'descr': '<f8', 'shape': (6,)}", "lacks 'fortran_order'"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,), 'x': 1}", "unexpected key 'x'"},
      {"{'descr': '<f8', 'descr': '<f8', 'fortran_order': False, 'shape': (6,)}", "repeats key"},
      {"{'descr': '|O', 'fortran_order': False, 'shape': (6,)}", "object"},
      {"{'descr': 'O', 'fortran_order': False, 'shape': (6,)}", "object"},
      {"{'descr': '<c16', 'fortran_order': False, 'shape': (3,)}", "complex"},
      {"{'descr': '<U2', 'fortran_order': False, 'shape': (6,)}", "string"},
      {"{'descr': '|V8', 'fortran_order': False, 'shape': (6,)}", "void"},
      {"{'descr': '<M8[s]', 'fortran_order': False, 'shape': (6,)}", "malformed"},
      {"{'descr': '<m8', 'fortran_order': False, 'shape': (6,)}", "datetime"},
      {"{'descr': '<f16', 'fortran_order': False, 'shape': (3,)}", "not supported"},
      {"{'descr': '<i3', 'fortran_order': False, 'shape': (16,)}", "unsupported size"},
      {"{'descr': '|f8', 'fortran_order': False, 'shape': (6,)}", "byte order '|'"},
      {"{'descr': '<x8', 'fortran_order': False, 'shape': (6,)}", "not a recognised"},
      {"{'descr': '', 'fortran_order': False, 'shape': (6,)}", "empty"},
      {"{'descr': '<', 'fortran_order': False, 'shape': (6,)}", "no type code"},
      {"{'descr': '<f', 'fortran_order': False, 'shape': (6,)}", "no item size"},
      {"{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (6,)}", "structured"},
      {"{'descr': 8, 'fortran_order': False, 'shape': (6,)}", "not a string"},
      {"{'descr': '<f8', 'fortran_order': 1, 'shape': (6,)}", "True/False"},
      {"{'descr': '<f8', 'fortran_order': None, 'shape': (6,)}", "True/False"},
      {"{'descr': '<f8', 'fortran_order': false, 'shape': (6,)}", "unexpected token"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': [6]}", "not a tuple"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6)}", "not a tuple"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (-6,)}", "negative"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6.0,)}", "malformed integer"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': ('6',)}", "non-integer"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (18446744073709551616,)}", "too large"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (1099511627776,)}", "shape"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296)}", "too large"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (4611686018427387904,)}", "too large"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (5,)}", "trailing bytes"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (7,)}", "only 48"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,)} x", "after the dict"},
      {"{'descr': '<f8', 'fortran_order': False 'shape': (6,)}", "expected ','"},
      {"{'descr': '<f8, 'fortran_order': False, 'shape': (6,)}", "expected"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,", "expected"},
      {"{'descr\\x': '<f8'}", "escape"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': " + std::string(40, '(') + "6" +
           std::string(40, ')') + "}",
       "nesting too deep"},
      {"['descr', '<f8']", "expected '{'"},
      {"{1: 2}", "string key"},
      {"", "expected '{'"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }\x01", "unexpected text"},
      {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,)" + std::string(1, '\0') + "}", "expected"},
  };
  for (const auto& b : bad) {
    CAPTURE(b.dict);
    const std::string msg = npyError(ok(b.dict));
    CHECK_THAT(msg, Catch::Contains(b.expect) && Catch::Contains("test.npy"));
  }

  const auto good = ok("{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }");
  auto wrong_magic = good;
  wrong_magic[5] = 'X';
  CHECK_THAT(npyError(wrong_magic), Catch::Contains("bad magic"));
  for (auto ver : std::vector<std::pair<int, int>>{{0, 0}, {4, 0}, {1, 1}, {255, 0}}) {
    auto v = good;
    v[6] = static_cast<uint8_t>(ver.first);
    v[7] = static_cast<uint8_t>(ver.second);
    CHECK_THAT(npyError(v), Catch::Contains("unsupported .npy version"));
  }
  auto long_header = good;
  io_test::patchLE(long_header, 8, 0xFFFF, 2);
  CHECK_THAT(npyError(long_header), Catch::Contains("exceeds the file size"));
  auto v2_huge = makeNpy("{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }", body, 2);
  io_test::patchLE(v2_huge, 8, 0xFFFFFFF0u, 4);
  CHECK_THAT(npyError(v2_huge), Catch::Contains("exceeds the file size"));
  CHECK_THAT(npyError(makeNpy("{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }", body, 1, false)),
             Catch::Contains("newline"));
  CHECK_THAT(npyError({}), Catch::Contains("too short"));
  CHECK_THAT(errorOf([] { hawor::parseNpy(nullptr, 0, "null.npy"); }), Catch::Contains("too short"));

  CHECK_THAT(errorOf([] { hawor::readNpyFile(io_test::tempPath("does_not_exist.npy")); }),
             Catch::Contains("does_not_exist.npy"));
}

TEST_CASE("npy truncated at every length throws hawor::Error", "[io][npy]") {
  std::mt19937 rng(7);
  const auto d = sampleValues<double>(12, rng);
  const auto s = sampleValues<int16_t>(5, rng);
  const bool bools[3] = {true, false, true};
  const std::vector<std::vector<uint8_t>> files = {
      hawor::writeNpy(NpyArray::fromData(d.data(), {3, 4}, true)),
      hawor::writeNpy(NpyArray::fromData(s.data(), {5}, false, true)),
      hawor::writeNpy(NpyArray::fromData(bools, {3})),
      makeNpy("{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }", f8Body({1, 2}), 3),
  };
  for (const auto& f : files) {
    REQUIRE(npyError(f) == "<no error>");
    int not_thrown = 0;
    for (size_t k = 0; k < f.size(); ++k) {
      std::vector<uint8_t> prefix(f.begin(), f.begin() + k);
      if (npyError(prefix) == "<no error>") ++not_thrown;
    }
    CHECK(not_thrown == 0);
  }
}

TEST_CASE("npy random corruption never crashes", "[io][npy]") {
  std::mt19937 rng(99);
  const auto d = sampleValues<double>(24, rng);
  const auto base = hawor::writeNpy(NpyArray::fromData(d.data(), {2, 3, 4}, true));
  int others = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    auto f = base;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t pos = rng() % (trial % 2 ? 80 : f.size());  // favour the header
      f[pos] = static_cast<uint8_t>(rng());
    }
    if (rng() % 8 == 0) f.resize(rng() % f.size());
    const int r = io_test::outcome([&] {
      const NpyArray a = hawor::parseNpy(f.data(), f.size(), "fuzz.npy");
      (void)a.as<double>();
      (void)a.as<int64_t>();
    });
    if (r == 2) ++others;
  }
  CHECK(others == 0);
}

TEST_CASE("npy writer validates arrays and files round trip on disk", "[io][npy]") {
  NpyArray bad;
  bad.dtype = "<f8";
  bad.shape = {3};
  bad.bytes.resize(16);
  CHECK_THAT(errorOf([&] { hawor::writeNpy(bad); }), Catch::Contains("needs 24"));
  CHECK_THAT(errorOf([&] { NpyArray::fromRaw("<f4", {2}, std::vector<uint8_t>(7)); }),
             Catch::Contains("holds 7 bytes"));
  CHECK_THAT(errorOf([&] { NpyArray::fromRaw("|O", {1}, std::vector<uint8_t>(8)); }),
             Catch::Contains("object"));
  NpyArray huge;
  huge.shape = {size_t(1) << 31, size_t(1) << 31, size_t(1) << 31};
  CHECK(io_test::outcome([&] { (void)huge.size(); }) == 1);

  const float v[4] = {1.5f, -2.25f, 3.0f, 1e-3f};
  const NpyArray a = NpyArray::fromData(v, {2, 2}, true, true);
  const std::string path = io_test::tempPath("npy_roundtrip.npy");
  hawor::writeNpyFile(path, a);
  const NpyArray b = hawor::readNpyFile(path);
  CHECK(b == a);
  CHECK(b.as<float>() == std::vector<float>(v, v + 4));
}
