// Cross-check of motion/infiller_net.hpp against onnxruntime-web (tests/support/infiller_ref.hpp:
// random weights and windows run by tests/ref/infiller_onnx.mjs in node); the C++ network loads
// the same .npz and must reproduce the outputs. Needs node and node_modules/onnxruntime-web
// (scripts/install.sh). (The AMX backend's check is tests/motion/amx_infiller.cpp.)
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "../support/infiller_ref.hpp"

TEST_CASE("infiller network matches onnxruntime (official sizes, random weights)",
          "[motion][infiller][ref]") {
  // windows: random gaps of 10-60 frames, 5 valid frames only, first half missing
  const int windows = 3;
  const auto ref = infiller_ref::runNodeReference("infiller_onnx.txt", "--windows 3 --seed 7");
  const std::string path = std::string(HAWOR_REF_DIR) + "/infiller_onnx.txt.npz";
  const hawor::Npz npz = hawor::Npz::read(path);
  std::remove(path.c_str());  // 139 MB of random weights
  const hawor::InfillerConfig official;
  double yMax = 0;
  const auto run = [&](auto scalar, hawor::MatmulBackend backend, int n, double tol,
                       const char* label, int threads = 1) {
    using S = decltype(scalar);
    const hawor::InfillerNet<S> net(hawor::loadInfillerWeights<S>(npz, official), backend);
    hawor::ThreadPool pool(threads);
    const double d = infiller_ref::maxDiff(net, ref, n, &yMax, &pool);
    std::printf("infiller vs onnxruntime (|y| <= %.3g): max |diff| %s %.3g\n", yMax, label, d);
    CHECK(d <= tol);
  };
  run(double(), hawor::MatmulBackend::Eigen, windows, 1e-4, "double/Eigen");
  run(float(), hawor::MatmulBackend::Eigen, windows, 1e-4, "float/Eigen");
  run(float(), hawor::MatmulBackend::Eigen, windows, 1e-4, "float/Eigen/2 threads", 2);
  // the WebAssembly backend (packed kernel), natively, on one masked window
  run(double(), hawor::MatmulBackend::Packed, 1, 1e-4, "double/Packed");
  run(float(), hawor::MatmulBackend::Packed, 1, 1e-4, "float/Packed");
}
