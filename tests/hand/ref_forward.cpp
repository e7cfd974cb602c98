// Cross-checks against numpy: the loader on synthetic MANO files written by Python (pickles with
// the official object layout in several protocol variants, .npz conversions) and the forward pass
// against an independent numpy implementation (tests/ref/hand_forward.py), right and left.
#include <catch2/catch.hpp>

#include "hawor/hand/forward.hpp"
#include "hawor/hand/mano_loader.hpp"
#include "hawor/hand/mirror.hpp"
#include "../support/ref_data.hpp"

#include <string>

namespace {

const std::string& modelDir() {
  static const std::string dir = std::string(HAWOR_REF_DIR) + "/hand_models";
  return dir;
}

// Reference arrays written by hand_make_mano.py (runs once per process).
const hawor_test::RefData& madeModels() {
  static const hawor_test::RefData r = hawor_test::runReference("hand_make_mano.py", "hand_make_mano.txt", modelDir());
  return r;
}

template <typename M>
double maxDiff(const M& m, const hawor_test::RefArray& ref) {
  REQUIRE(static_cast<long>(m.size()) == ref.size());
  double d = 0.0;
  long i = 0;
  // ref is row-major; read m in row-major order too.
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) d = std::max(d, std::abs(double(m(r, c)) - ref[i++]));
  return d;
}

void checkModel(const hawor::HandModeld& m, const std::string& prefix, bool left, double tol = 0.0) {
  const auto& r = madeModels();
  CHECK(m.numVertices() == 778);
  CHECK(m.numJoints() == 16);
  CHECK(m.numBetas() == 10);
  CHECK(m.isLeft == left);
  CHECK(maxDiff(m.vTemplate, r[prefix + "v_template"]) <= tol);
  CHECK(maxDiff(m.shapedirs, r[prefix + "shapedirs"]) <= tol);  // (778,3,10) row-major = (2334,10)
  CHECK(maxDiff(m.jRegressor, r[prefix + "J_regressor"]) <= tol);
  CHECK(maxDiff(m.weights, r[prefix + "weights"]) <= tol);
  // Faces: the file's faces; a left model stores the [0,2,1] winding.
  const hawor::Faces f = left ? hawor::flipFaceWinding(m.faces) : m.faces;
  CHECK(maxDiff(f.cast<double>(), r[prefix + "faces"]) == 0.0);
  const auto& par = r[prefix + "parents"];
  for (int j = 0; j < 16; ++j) CHECK(m.parents[static_cast<std::size_t>(j)] == static_cast<int>(par[j]));
  CHECK(m.numKeypoints() == 21);
}

void checkPosedirs(const hawor::HandModeld& m, const std::string& name) {
  const auto& r = madeModels();
  const auto& probe = r["probe"];
  Eigen::VectorXd x(probe.size());
  for (long i = 0; i < probe.size(); ++i) x(i) = probe[i];
  const Eigen::VectorXd y = m.posedirs * x;
  CHECK(maxDiff(y, r[name]) <= 1e-14);
}

hawor::HandModeld loadFile(const std::string& file, hawor::ManoLoadOptions opt = {}) {
  (void)madeModels();  // writes the files on first use
  return hawor::loadMano<double>(modelDir() + "/" + file, opt);
}

}  // namespace

TEST_CASE("hand ref: Python-written MANO pickles load exactly", "[hand][ref]") {
  const auto right = loadFile("MANO_RIGHT.pkl");
  checkModel(right, "", false);
  checkPosedirs(right, "posedirs_probe");
  const auto left = loadFile("MANO_LEFT.pkl");  // carries the released file's shapedirs bug
  checkModel(left, "L_", true);
  checkPosedirs(left, "L_posedirs_probe");
  // Python 3 pickler at protocols 0 (text, _codecs.encode, copy_reg._reconstructor), 2 and 4.
  for (const char* f : {"MANO_RIGHT_p0.pkl", "MANO_RIGHT_p2.pkl", "MANO_RIGHT_p4.pkl"}) {
    INFO(f);
    const auto m = loadFile(f);
    checkModel(m, "", false);
    checkPosedirs(m, "posedirs_probe");
  }
  // Big-endian v_template, Fortran weights, float32 posedirs, csc 'shape' key.
  const auto odd = loadFile("MANO_RIGHT_odd.pkl");
  checkModel(odd, "", false);
  checkPosedirs(odd, "odd_posedirs_probe");
  // .npz conversions (stored and deflated), with the same left fix.
  checkModel(loadFile("mano_right.npz"), "", false);
  checkModel(loadFile("mano_left.npz"), "L_", true);
  checkPosedirs(hawor::loadManoNpz<double>(modelDir() + "/mano_left.npz"), "L_posedirs_probe");
  // float models.
  const auto rf = hawor::loadMano<float>(modelDir() + "/MANO_RIGHT.pkl");
  CHECK(maxDiff(rf.vTemplate, madeModels()["v_template"]) < 1e-7);
}

TEST_CASE("hand ref: forward pass matches numpy (right, left, pkl, npz)", "[hand][ref]") {
  (void)madeModels();
  const auto ref = hawor_test::runReference("hand_forward.py", "hand_forward.txt", modelDir());
  const auto& pose = ref["pose"];
  const auto& betas = ref["betas"];
  const auto& transl = ref["transl"];
  const long n = pose.shape[0];
  struct Case {
    const char* file;
    const char* prefix;
  };
  for (const Case c : {Case{"MANO_RIGHT.pkl", "R_"}, Case{"mano_right.npz", "R_"}, Case{"MANO_RIGHT_p0.pkl", "R_"},
                       Case{"MANO_LEFT.pkl", "L_"}, Case{"mano_left.npz", "L_"}}) {
    INFO(c.file);
    const auto model = loadFile(c.file);
    hawor::ManoLoadOptions noFix;
    noFix.fixLeftShapedirs = false;
    const auto unfixed = loadFile(c.file, noFix);
    hawor::HandWorkspace<double> ws;
    hawor::HandOutput<double> out;
    const std::string p = c.prefix;
    for (long i = 0; i < n; ++i) {
      INFO("case " << i);
      auto hp = hawor::HandPose<double>::zero(model);
      for (int c3 = 0; c3 < 3; ++c3) {
        hp.rot(c3) = pose[i * 48 + c3];
        hp.trans(c3) = transl[i * 3 + c3];
      }
      for (int j = 1; j < 16; ++j)
        for (int c3 = 0; c3 < 3; ++c3) hp.handPose(j - 1, c3) = pose[i * 48 + j * 3 + c3];
      for (int k = 0; k < 10; ++k) hp.betas(k) = betas[i * 10 + k];
      hawor::forward(model, hp, ws, out);
      double dv = 0, dj = 0, dk = 0;
      for (long k = 0; k < 778 * 3; ++k) dv = std::max(dv, std::abs(out.vertices.data()[k] - ref[p + "verts"][i * 778 * 3 + k]));
      for (long k = 0; k < 16 * 3; ++k) dj = std::max(dj, std::abs(out.joints.data()[k] - ref[p + "joints"][i * 16 * 3 + k]));
      for (long k = 0; k < 21 * 3; ++k) dk = std::max(dk, std::abs(out.keypoints.data()[k] - ref[p + "kp"][i * 21 * 3 + k]));
      CHECK(dv <= 1e-10);
      CHECK(dj <= 1e-10);
      CHECK(dk <= 1e-10);
      // The left file's shapedirs fix matters whenever the shape is not the mean.
      if (p == "L_" && hp.betas.norm() > 0) {
        const auto bad = hawor::forward(unfixed, hp);
        double d = 0;
        for (long k = 0; k < 778 * 3; ++k) d = std::max(d, std::abs(bad.vertices.data()[k] - ref[p + "verts"][i * 778 * 3 + k]));
        CHECK(d > 1e-4);
      }
    }
  }
}
