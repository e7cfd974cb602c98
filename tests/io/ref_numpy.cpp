// numpy <-> hawor: we read what np.save / np.savez / np.savez_compressed write (every dtype,
// Fortran order, big-endian, bool, 0-d and empty arrays, format versions 1-3), and numpy reads
// what we write (np.load, zipfile CRC checks), compared byte for byte. Values come from
// tests/ref/io_numpy.py; nothing here is pasted from the library.
#include <catch2/catch.hpp>

#include <hawor/io/io.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "../support/ref_data.hpp"

using hawor::NpyArray;
using hawor_test::RefArray;

namespace {

std::string decode(const RefArray& codes) {
  std::string s;
  for (double c : codes.data) s += static_cast<char>(static_cast<int>(c));
  return s;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t b = 0;
  for (size_t i = 0; i <= s.size(); ++i) {
    if (i == s.size() || s[i] == ',') {
      out.push_back(s.substr(b, i - b));
      b = i + 1;
    }
  }
  return out;
}

std::vector<size_t> shapeOf(const RefArray& r) {
  return std::vector<size_t>(r.shape.begin(), r.shape.end());
}

bool sameDouble(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return a == b && std::signbit(a) == std::signbit(b);
}

// The reference values stored as dtype T in the requested memory and byte order.
template <typename T>
NpyArray build(const RefArray& r, bool fortran, bool big) {
  std::unique_ptr<T[]> v(new T[r.data.size() + 1]);
  for (size_t i = 0; i < r.data.size(); ++i) v[i] = static_cast<T>(r.data[i]);
  return NpyArray::fromData(v.get(), shapeOf(r), fortran, big);
}

NpyArray buildAs(const hawor::NpyType& t, const RefArray& r, bool fortran) {
  const bool be = t.big_endian;
  switch (t.kind) {
    case hawor::NpyKind::Bool: return build<bool>(r, fortran, be);
    case hawor::NpyKind::Int:
      switch (t.itemsize) {
        case 1: return build<int8_t>(r, fortran, be);
        case 2: return build<int16_t>(r, fortran, be);
        case 4: return build<int32_t>(r, fortran, be);
        default: return build<int64_t>(r, fortran, be);
      }
    case hawor::NpyKind::UInt:
      switch (t.itemsize) {
        case 1: return build<uint8_t>(r, fortran, be);
        case 2: return build<uint16_t>(r, fortran, be);
        case 4: return build<uint32_t>(r, fortran, be);
        default: return build<uint64_t>(r, fortran, be);
      }
    default: return t.itemsize == 4 ? build<float>(r, fortran, be) : build<double>(r, fortran, be);
  }
}

// Checks an array read by hawor against the reference: dtype string, shape, order, values.
void checkArray(const NpyArray& a, const RefArray& r, const std::string& dtype, bool fortran) {
  CHECK(a.dtype == dtype);
  CHECK(a.shape == shapeOf(r));
  CHECK(a.fortran_order == fortran);
  const std::vector<double> v = a.as<double>();
  REQUIRE(v.size() == r.data.size());
  for (size_t i = 0; i < v.size(); ++i) {
    CAPTURE(i, v[i], r.data[i]);
    CHECK(sameDouble(v[i], r.data[i]));
  }
  const hawor::NpyType t = a.type();
  if (t.kind == hawor::NpyKind::Int) {  // exact integers, not only their float64 images
    const auto iv = a.as<int64_t>();
    for (size_t i = 0; i < iv.size(); ++i) CHECK(iv[i] == static_cast<int64_t>(r.data[i]));
  } else if (t.kind == hawor::NpyKind::UInt) {
    const auto uv = a.as<uint64_t>();
    for (size_t i = 0; i < uv.size(); ++i) CHECK(uv[i] == static_cast<uint64_t>(r.data[i]));
  }
}

}  // namespace

TEST_CASE("numpy reads hawor's .npy/.npz and hawor reads numpy's", "[io][ref][npz]") {
  const std::string dir = std::string(HAWOR_REF_DIR) + "/io_numpy";
  const auto ref = hawor_test::runReference("io_numpy.py", "io_numpy_make.txt", "make " + dir);
  const std::vector<std::string> names = split(decode(ref["names"]));
  REQUIRE(names.size() >= 20);

  // numpy -> hawor: np.save, np.savez, np.savez_compressed.
  const hawor::Npz stored = hawor::Npz::read(dir + "/np_stored.npz");
  const hawor::Npz compressed = hawor::Npz::read(dir + "/np_compressed.npz");
  CHECK(stored.names() == names);
  CHECK(compressed.names() == names);
  {
    // numpy's members carry ZIP64 extras in their local headers and deflate with zlib.
    const auto bytes = hawor::readFileBytes(dir + "/np_compressed.npz");
    const hawor::ZipReader zr(bytes.data(), bytes.size(), "np_compressed.npz");
    CHECK(zr.entries().back().method == 8);
  }
  hawor::Npz ours;
  size_t written = 0;
  for (const auto& name : names) {
    CAPTURE(name);
    const RefArray& r = ref[name];
    const std::string dtype = decode(ref["dtype_" + name]);
    const bool fortran = ref["fortran_" + name][0] != 0;
    const NpyArray a = hawor::readNpyFile(dir + "/np_" + name + ".npy");
    checkArray(a, r, dtype, fortran);
    CHECK(stored.get(name) == a);
    CHECK(compressed.get(name) == a);

    // hawor -> numpy: the same values, dtype, byte order and memory order, built from the
    // reference values (float16 has no C++ type to build from).
    const hawor::NpyType t = hawor::NpyType::parse(dtype, name);
    if (t.kind == hawor::NpyKind::Float && t.itemsize == 2) continue;
    const NpyArray b = buildAs(t, r, fortran);
    CHECK(b.dtype == dtype);
    CHECK(b == a);  // element bytes identical to numpy's
    hawor::writeNpyFile(dir + "/cpp_" + name + ".npy", b);
    ours.set(name, b);
    ++written;
  }
  for (int v : {2, 3}) {
    const NpyArray a = hawor::readNpyFile(dir + "/np_v" + std::to_string(v) + ".npy");
    CHECK(a == hawor::readNpyFile(dir + "/np_f8_f.npy"));
  }
  ours.write(dir + "/cpp_stored.npz", false);
  ours.write(dir + "/cpp_compressed.npz", true);
  hawor::writeFileBytes(dir + "/cpp_zip64.npz", ours.toBuffer(true, true));

  const auto res = hawor_test::runReference("io_numpy.py", "io_numpy_check.txt", "check " + dir);
  CHECK(res["checked"][0] == static_cast<double>(written + 3));
  CHECK(res["failures"][0] == 0);  // details on stderr
}
