// The onnxruntime reference of the infiller network for the C++ cross-checks
// (tests/motion/ref_infiller_net.cpp, tests/motion/amx_infiller.cpp): tests/ref/infiller_onnx.mjs
// builds the network as ONNX with random weights (web/tools/make_infiller_model.mjs), runs
// random windows with random validity masks in node, and writes the weights (.npz), inputs and
// outputs. Needs node and node_modules/onnxruntime-web (scripts/install.sh), and the test
// target's HAWOR_SOURCE_DIR / HAWOR_REF_DIR definitions.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "ref_data.hpp"
#include "hawor/motion/infiller_net.hpp"

namespace infiller_ref {

// Runs `node tests/ref/infiller_onnx.mjs <out> args` and loads what it wrote (the weights are in
// <out>.npz).
inline hawor_test::RefData runNodeReference(const std::string& outName, const std::string& args) {
  const std::string out = std::string(HAWOR_REF_DIR) + "/" + outName;
  const std::string cmd =
      "node " + std::string(HAWOR_SOURCE_DIR) + "/tests/ref/infiller_onnx.mjs " + out + " " + args;
  const int rc = std::system(cmd.c_str());
  if (rc != 0)
    throw std::runtime_error(
        "reference script failed (node and node_modules/onnxruntime-web "
        "are needed: scripts/install.sh): " +
        cmd);
  return hawor_test::RefData::load(out);
}

template <typename S>
hawor::RowMatrixX<S> asMatrix(const hawor_test::RefArray& a) {
  hawor::RowMatrixX<S> m(a.shape.at(0), a.shape.at(1));
  for (long i = 0; i < a.size(); ++i) m.data()[i] = static_cast<S>(a[i]);
  return m;
}

inline hawor::ValidMask asMask(const hawor_test::RefArray& a) {
  hawor::ValidMask v(static_cast<size_t>(a.size()));
  for (long i = 0; i < a.size(); ++i) v[static_cast<size_t>(i)] = a[i] > 0.5 ? 1 : 0;
  return v;
}

// max |C++ − onnxruntime| over windows [0, windows) and the largest |y| (for scale).
template <typename S>
double maxDiff(const hawor::InfillerNet<S>& net, const hawor_test::RefData& ref, int windows,
               double* maxAbs = nullptr, hawor::ThreadPool* pool = nullptr) {
  hawor::InfillerWorkspace<S> ws(net.config(), pool ? pool->size() : 1);
  hawor::RowMatrixX<S> y;
  double worst = 0, big = 0;
  for (int i = 0; i < windows; ++i) {
    const std::string k = std::to_string(i);
    const auto x = asMatrix<S>(ref["x" + k]);
    net.forward(x, asMask(ref["valid" + k]), y, ws, pool);
    const Eigen::MatrixXd expect = asMatrix<double>(ref["y" + k]);
    worst = std::max(worst, (y.template cast<double>() - expect).cwiseAbs().maxCoeff());
    big = std::max(big, expect.cwiseAbs().maxCoeff());
  }
  if (maxAbs) *maxAbs = big;
  return worst;
}

}  // namespace infiller_ref
