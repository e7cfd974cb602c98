// Writes the seed corpora of the io fuzz targets: valid files of each kind, from the library's
// own writers. Usage: hawor_fuzz_seeds <dir>  ->  <dir>/npy/*.npy, <dir>/npz/*.npz, <dir>/tum/*.txt
#include <hawor/io/io.hpp>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <seed dir>\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  try {
    const double d[12] = {1.5, -2, 0, 1e-300, 3, 4, 5, 6, 7, 8, 9, 10};
    const int32_t i[6] = {-1, 2, 3, 4, 5, 2147483647};
    const uint16_t u[3] = {1, 2, 65535};
    const bool b[4] = {true, false, true, true};
    const float f[2] = {0.5f, -1e30f};
    std::vector<hawor::NpyArray> arrays = {
        hawor::NpyArray::fromData(d, {3, 4}),
        hawor::NpyArray::fromData(d, {2, 3, 2}, true),
        hawor::NpyArray::fromData(i, {2, 3}, true, true),
        hawor::NpyArray::fromData(u, {3}, false, true),
        hawor::NpyArray::fromData(b, {2, 2}),
        hawor::NpyArray::fromData(f, {}),
        hawor::NpyArray::fromData(d, {0, 3}),
        hawor::NpyArray::fromRaw("<f2", {2}, {0x00, 0x3C, 0x00, 0xC0}),
    };
    hawor::Npz z;
    for (size_t k = 0; k < arrays.size(); ++k) {
      hawor::writeNpyFile(dir + "/npy/seed" + std::to_string(k) + ".npy", arrays[k]);
      hawor::Npz one;
      one.set("a", arrays[k]);
      hawor::writeFileBytes(dir + "/npz/one" + std::to_string(k) + ".npz", one.toBuffer(k % 2 == 1, k % 3 == 0));
      z.set("arr" + std::to_string(k), arrays[k]);
    }
    hawor::writeFileBytes(dir + "/npz/all_stored.npz", z.toBuffer(false));
    hawor::writeFileBytes(dir + "/npz/all_deflated.npz", z.toBuffer(true));
    hawor::writeFileBytes(dir + "/npz/all_zip64.npz", z.toBuffer(true, true));

    std::vector<hawor::TumPose<double>> traj(5);
    for (size_t k = 0; k < traj.size(); ++k) {
      traj[k].t = 1305031102.175304 + 0.033 * static_cast<double>(k);
      traj[k].p = hawor::Vec3<double>(0.1 * k, -0.2, 1e-3 * k);
      traj[k].q = Eigen::Quaternion<double, Eigen::DontAlign>(1, 0.1 * k, 0, -0.05);
      traj[k].q.normalize();
    }
    hawor::writeTum(dir + "/tum/traj.txt", traj);
    hawor::writeFileText(dir + "/tum/mixed.txt",
                         "# comment\n\n0 1 2 3 0 0 0 1\r\n1.5\t-1e-3 2e5 0 0.5 0.5 0.5 0.5\n");
  } catch (const hawor::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
