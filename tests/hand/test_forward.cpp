// Forward pass properties (float and double) and the left/right mirror convention.
#include <catch2/catch.hpp>

#include "hand_test_util.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/mirror.hpp"

template struct hawor::HandModel<float>;
template struct hawor::HandModel<double>;
template struct hawor::HandPose<float>;
template struct hawor::HandPose<double>;
template struct hawor::HandOutput<float>;
template struct hawor::HandOutput<double>;
template struct hawor::HandWorkspace<float>;
template struct hawor::HandWorkspace<double>;

namespace {

template <typename Scalar>
double fwdTol() {
  return std::is_same<Scalar, float>::value ? 2e-5 : 1e-12;
}

template <typename A, typename B>
double fwdMaxAbs(const A& a, const B& b) {
  return (a.template cast<double>() - b.template cast<double>()).cwiseAbs().maxCoeff();
}

}  // namespace

TEMPLATE_TEST_CASE("hand forward: zero pose and shape give the template", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  const auto out = hawor::forward(m, hawor::HandPose<S>::zero(m));
  CHECK(fwdMaxAbs(out.vertices, m.vTemplate) <= fwdTol<S>());
  const hawor::Points3<S> jr = m.jRegressor * m.vTemplate;
  CHECK(fwdMaxAbs(out.joints, jr) <= fwdTol<S>());
  REQUIRE(out.keypoints.rows() == 21);
  // Keypoint map: wrist, thumb chain then its tip vertex 744, ..., pinky tip 671 last.
  CHECK(fwdMaxAbs(out.keypoints.row(0), out.joints.row(0)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(1), out.joints.row(13)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(4), out.vertices.row(744)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(8), out.vertices.row(320)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(12), out.vertices.row(443)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(16), out.vertices.row(554)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(17), out.joints.row(7)) == 0.0);
  CHECK(fwdMaxAbs(out.keypoints.row(20), out.vertices.row(671)) == 0.0);
}

TEMPLATE_TEST_CASE("hand forward: shape blend and joint regression", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  auto p = hawor::HandPose<S>::zero(m);
  p.betas = hawor::VecX<S>::LinSpaced(m.numBetas(), S(-2), S(2));
  const auto out = hawor::forward(m, p);
  const hawor::VecX<S> flat = m.shapedirs * p.betas;
  hawor::Points3<S> expect = m.vTemplate;
  for (int v = 0; v < m.numVertices(); ++v)
    for (int c = 0; c < 3; ++c) expect(v, c) += flat(3 * v + c);
  CHECK(fwdMaxAbs(out.vertices, expect) <= fwdTol<S>());
  const hawor::Points3<S> jr = m.jRegressor * expect;
  CHECK(fwdMaxAbs(out.joints, jr) <= fwdTol<S>());
  // Fewer betas than the model has = the missing ones are zero (equal up to rounding: the
  // products may group the terms differently, e.g. the plain-loop kernels of the WASM build).
  auto p3 = p;
  p3.betas = p.betas.head(3);
  auto p3full = p;
  p3full.betas.tail(m.numBetas() - 3).setZero();
  CHECK(fwdMaxAbs(hawor::forward(m, p3).vertices, hawor::forward(m, p3full).vertices) <= fwdTol<S>());
}

TEMPLATE_TEST_CASE("hand forward: translation shifts every output", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  auto p = hand_test::randomPose(m, 3);
  p.trans.setZero();
  const auto a = hawor::forward(m, p);
  p.trans = hawor::Vec3<S>(S(0.3), S(-1.2), S(2.5));
  const auto b = hawor::forward(m, p);
  const Eigen::Matrix<S, 1, 3> t = p.trans.transpose();
  CHECK(fwdMaxAbs(b.vertices, a.vertices.rowwise() + t) <= 4 * fwdTol<S>());
  CHECK(fwdMaxAbs(b.joints, a.joints.rowwise() + t) <= 4 * fwdTol<S>());
  CHECK(fwdMaxAbs(b.keypoints, a.keypoints.rowwise() + t) <= 4 * fwdTol<S>());
}

TEMPLATE_TEST_CASE("hand forward: global orientation rotates about joint 0", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  auto p = hand_test::randomPose(m, 4);
  p.trans.setZero();
  p.rot.setZero();
  const auto a = hawor::forward(m, p);
  p.rot = hawor::Vec3<S>(S(0.4), S(-1.1), S(2.0));
  const auto b = hawor::forward(m, p);
  // Joint 0 stays where it was; everything else is rotated about it (correctives ignore joint 0).
  CHECK(fwdMaxAbs(b.joints.row(0), a.joints.row(0)) <= fwdTol<S>());
  const hawor::Mat3<S> R = hawor::axisAngleToMatrix(p.rot);
  const Eigen::Matrix<S, 1, 3> j0 = a.joints.row(0);
  const hawor::Points3<S> expect = ((a.vertices.rowwise() - j0) * R.transpose()).rowwise() + j0;
  CHECK(fwdMaxAbs(b.vertices, expect) <= 4 * fwdTol<S>());
}

TEMPLATE_TEST_CASE("hand forward: without finger pose the hand moves rigidly", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  // Rows of the skinning weights sum to 1, so equal joint transforms move every vertex by them.
  for (int v = 0; v < m.numVertices(); ++v) REQUIRE(std::abs(double(m.weights.row(v).sum()) - 1.0) < 1e-5);
  auto p = hand_test::randomPose(m, 5);
  p.handPose.setZero();
  const auto out = hawor::forward(m, p);
  auto rest = hawor::HandPose<S>::zero(m);
  rest.betas = p.betas;
  const auto shaped = hawor::forward(m, rest);
  const hawor::Mat3<S> R = hawor::axisAngleToMatrix(p.rot);
  const Eigen::Matrix<S, 1, 3> j0 = shaped.joints.row(0);
  const hawor::Points3<S> expect =
      (((shaped.vertices.rowwise() - j0) * R.transpose()).rowwise() + j0).rowwise() + p.trans.transpose();
  CHECK(fwdMaxAbs(out.vertices, expect) <= 4 * fwdTol<S>());
  // Distances between vertices are preserved.
  for (int k = 0; k < 50; ++k) {
    const int i = (k * 37) % m.numVertices(), j = (k * 101 + 5) % m.numVertices();
    const double d0 = double((shaped.vertices.row(i) - shaped.vertices.row(j)).norm());
    const double d1 = double((out.vertices.row(i) - out.vertices.row(j)).norm());
    CHECK(std::abs(d0 - d1) <= 4 * fwdTol<S>());
  }
}

TEMPLATE_TEST_CASE("hand forward: kinematic chain and skinning locality", "[hand][forward]", float, double) {
  using S = TestType;
  auto m = hand_test::randomModel<S>();
  m.posedirs.resize(0, 0);  // no correctives: only skinning moves vertices
  m.prepare();
  auto p = hawor::HandPose<S>::zero(m);
  const auto rest = hawor::forward(m, p);
  // Rotate the index base (joint 1): joints 2, 3 turn about joint 1, nothing else moves.
  p.handPose.row(0) << S(0.3), S(-0.5), S(0.8);
  const auto out = hawor::forward(m, p);
  const hawor::Mat3<S> R = hawor::axisAngleToMatrix(p.handPose.row(0).transpose());
  for (int j = 0; j < 16; ++j) {
    hawor::Vec3<S> expect = rest.joints.row(j).transpose();
    if (j == 2 || j == 3) {
      const hawor::Vec3<S> j1 = rest.joints.row(1).transpose();
      expect = R * (expect - j1) + j1;
    }
    CHECK(fwdMaxAbs(out.joints.row(j), expect.transpose()) <= 4 * fwdTol<S>());
  }
  int moved = 0;
  for (int v = 0; v < m.numVertices(); ++v) {
    const bool attached = m.weights(v, 1) != S(0) || m.weights(v, 2) != S(0) || m.weights(v, 3) != S(0);
    const double d = fwdMaxAbs(out.vertices.row(v), rest.vertices.row(v));
    if (!attached) CHECK(d <= fwdTol<S>());
    if (attached && d > 1e-4) ++moved;
  }
  CHECK(moved > 0);
  // A vertex fully attached to joint 3 follows joint 3's frame rigidly.
  for (int v = 0; v < m.numVertices(); ++v) {
    if (m.weights(v, 3) == S(1)) {
      const hawor::Vec3<S> j1 = rest.joints.row(1).transpose();
      const hawor::Vec3<S> expect = R * (rest.vertices.row(v).transpose() - j1) + j1;
      CHECK(fwdMaxAbs(out.vertices.row(v), expect.transpose()) <= 4 * fwdTol<S>());
    }
  }
}

TEMPLATE_TEST_CASE("hand forward: pose correctives use row-major (R - I) features", "[hand][forward]", float, double) {
  using S = TestType;
  auto m = hand_test::randomModel<S>();
  // Make skinning the identity (all weight on the root) to isolate the corrective term.
  m.weights.setZero();
  m.weights.col(0).setOnes();
  m.prepare();
  auto p = hand_test::randomPose(m, 6);
  p.rot.setZero();
  p.trans.setZero();
  const auto out = hawor::forward(m, p);
  hawor::VecX<S> f(9 * 15);
  for (int j = 1; j < 16; ++j) {
    const hawor::Mat3<S> R = hawor::axisAngleToMatrix(p.handPose.row(j - 1).transpose());
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f(9 * (j - 1) + 3 * r + c) = R(r, c) - (r == c ? S(1) : S(0));
  }
  const hawor::VecX<S> shaped = m.shapedirs * p.betas;
  const hawor::VecX<S> corr = m.posedirs * f;
  for (int v = 0; v < m.numVertices(); ++v)
    for (int c = 0; c < 3; ++c) {
      const double e = double(m.vTemplate(v, c) + shaped(3 * v + c) + corr(3 * v + c));
      REQUIRE(std::abs(double(out.vertices(v, c)) - e) <= 4 * fwdTol<S>());
    }
}

TEMPLATE_TEST_CASE("hand forward: split stages, reuse and errors", "[hand][forward]", float, double) {
  using S = TestType;
  const auto m = hand_test::randomModel<S>();
  const auto p = hand_test::randomPose(m, 7);
  hawor::HandWorkspace<S> ws;
  hawor::HandOutput<S> out;
  hawor::forward(m, p, ws, out);
  const auto once = hawor::forward(m, p);
  CHECK(fwdMaxAbs(out.vertices, once.vertices) == 0.0);
  // Same buffers on a second call; shape once, pose many.
  const S* vbuf = out.vertices.data();
  hawor::forward(m, hand_test::randomPose(m, 8), ws, out);
  CHECK(out.vertices.data() == vbuf);
  hawor::shapeHand(m, p.betas, ws);
  std::vector<hawor::Mat3<S>> rot(16);
  rot[0] = hawor::axisAngleToMatrix(p.rot);
  for (int j = 1; j < 16; ++j) rot[static_cast<std::size_t>(j)] = hawor::axisAngleToMatrix(p.handPose.row(j - 1).transpose());
  hawor::poseHand(m, rot.data(), p.trans, ws, out);
  CHECK(fwdMaxAbs(out.vertices, once.vertices) == 0.0);

  // Batch of frames = frame by frame (up to the summation order of the corrective product).
  std::vector<hawor::HandPose<S>> poses;
  for (unsigned k = 0; k < 5; ++k) poses.push_back(hand_test::randomPose(m, 40 + k));
  poses[2].betas = poses[2].betas.head(4).eval();
  std::vector<hawor::HandOutput<S>> outs(poses.size());
  hawor::HandBatchWorkspace<S> bws;
  hawor::forwardBatch(m, poses.data(), static_cast<int>(poses.size()), bws, outs.data());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto single = hawor::forward(m, poses[k]);
    CHECK(fwdMaxAbs(outs[k].vertices, single.vertices) <= 4 * fwdTol<S>());
    CHECK(fwdMaxAbs(outs[k].joints, single.joints) <= 4 * fwdTol<S>());
    CHECK(fwdMaxAbs(outs[k].keypoints, single.keypoints) <= 4 * fwdTol<S>());
  }
  hawor::forwardBatch(m, poses.data(), 0, bws, outs.data());
  poses[3].handPose(2, 2) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(hawor::forwardBatch(m, poses.data(), 5, bws, outs.data()), hawor::Error);

  hawor::HandModel<S> raw = m;
  raw.parents = m.parents;  // copies are prepared too
  CHECK(raw.prepared());
  hawor::HandModel<S> fresh;
  CHECK_THROWS_AS(hawor::forward(fresh, p), hawor::Error);
  auto bad = p;
  bad.handPose.resize(14, 3);
  CHECK_THROWS_AS(hawor::forward(m, bad), hawor::Error);
  bad = p;
  bad.betas.resize(11);
  bad.betas.setZero();
  CHECK_THROWS_AS(hawor::forward(m, bad), hawor::Error);
  bad = p;
  bad.rot(1) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(hawor::forward(m, bad), hawor::Error);
  bad = p;
  bad.betas(2) = std::numeric_limits<S>::infinity();
  CHECK_THROWS_AS(hawor::forward(m, bad), hawor::Error);
  auto edited = m;
  edited.shapedirs.conservativeResize(Eigen::NoChange, 4);  // edited without prepare()
  auto p3 = p;
  p3.betas = p.betas.head(3).eval();
  CHECK_NOTHROW(hawor::forward(m, p3));
  CHECK_THROWS_WITH(hawor::forward(edited, p3), Catch::Contains("changed since prepare"));
  hawor::HandWorkspace<S> unshaped;
  CHECK_THROWS_AS(hawor::poseHand(m, rot.data(), p.trans, unshaped, out), hawor::Error);
  // float agrees with double.
  if (std::is_same<S, float>::value) {
    const auto md = hawor::castHandModel<double>(m);
    hawor::HandPose<double> pd;
    pd.rot = p.rot.template cast<double>();
    pd.handPose = p.handPose.template cast<double>();
    pd.betas = p.betas.template cast<double>();
    pd.trans = p.trans.template cast<double>();
    CHECK(fwdMaxAbs(hawor::forward(md, pd).vertices, once.vertices) < 1e-4);
  }
}

TEMPLATE_TEST_CASE("hand forward: plain-loop product kernel (the WebAssembly path)", "[hand][forward]", float, double) {
  using S = TestType;
  // Y += A·X against Eigen's product, for row counts around the tile size and frame counts
  // that exercise the groups of 4 and the single-frame remainder, with strided X and Y.
  for (const Eigen::Index rows : {1, 7, 128, 129, 300}) {
    for (const Eigen::Index cols : {1, 5, 9, 16}) {
      for (const Eigen::Index n : {1, 3, 4, 5, 9}) {
        const hawor::MatX<S> A = hawor::MatX<S>::Random(rows, cols);
        const hawor::MatX<S> Xfull = hawor::MatX<S>::Random(cols + 2, n + 1);
        const hawor::MatX<S> Y0 = hawor::MatX<S>::Random(rows + 3, n);
        hawor::MatX<S> Y = Y0;
        const auto X = Xfull.topLeftCorner(cols, n);
        hawor::hand_detail::addProductLoops(A.data(), rows, cols, X.data(), Xfull.rows(), n, Y.data(), Y.rows());
        hawor::MatX<S> expect = Y0;
        expect.topRows(rows).noalias() += A * X;
        REQUIRE(fwdMaxAbs(Y, expect) <= S(cols) * 4 * std::numeric_limits<S>::epsilon() * 4);
      }
    }
  }
}

TEMPLATE_TEST_CASE("hand forward: batches across blocks and the shape cache", "[hand][forward]", float, double) {
  using S = TestType;
  auto m = hand_test::randomModel<S>();
  // 150 frames: two full blocks of 64 and a short one; runs of equal β (the cache) and changes.
  std::vector<hawor::HandPose<S>> poses;
  for (unsigned k = 0; k < 150; ++k) {
    poses.push_back(hand_test::randomPose(m, 100 + k));
    if (k % 7 != 0) poses.back().betas = poses[k - k % 7].betas;
  }
  std::vector<hawor::HandOutput<S>> outs(poses.size());
  hawor::HandBatchWorkspace<S> bws;
  hawor::forwardBatch(m, poses.data(), static_cast<int>(poses.size()), bws, outs.data());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto single = hawor::forward(m, poses[k]);  // fresh workspace: no cache involved
    REQUIRE(fwdMaxAbs(outs[k].vertices, single.vertices) <= 4 * fwdTol<S>());
    REQUIRE(fwdMaxAbs(outs[k].keypoints, single.keypoints) <= 4 * fwdTol<S>());
  }
  // The cache must not survive a change of β, of the model, or of the model's data in place.
  hawor::HandWorkspace<S> ws;
  hawor::HandOutput<S> out;
  const auto p = poses[0];
  hawor::forward(m, p, ws, out);
  auto q = p;
  q.betas(1) += S(0.5);
  hawor::forward(m, q, ws, out);
  CHECK(fwdMaxAbs(out.vertices, hawor::forward(m, q).vertices) == 0.0);
  q.betas = q.betas.head(3).eval();  // shorter β = the rest zero: a different shape
  hawor::forward(m, q, ws, out);
  CHECK(fwdMaxAbs(out.vertices, hawor::forward(m, q).vertices) == 0.0);
  hawor::forward(m, p, ws, out);
  m.vTemplate.array() += S(0.01);  // edited in place and prepared again at the same address
  m.prepare();
  hawor::forward(m, p, ws, out);
  CHECK(fwdMaxAbs(out.vertices, hawor::forward(m, p).vertices) == 0.0);
  const auto m2 = m;  // a copy (another address) with the same data
  hawor::forward(m2, p, ws, out);
  CHECK(fwdMaxAbs(out.vertices, hawor::forward(m, p).vertices) == 0.0);
}

TEMPLATE_TEST_CASE("hand model: validate() names what is wrong", "[hand][model]", float, double) {
  using S = TestType;
  const auto good = hand_test::randomModel<S>(40, {-1, 0, 1, 0, 3}, 4, true, 3);
  CHECK_NOTHROW(good.validate());
  CHECK(good.numKeypoints() == 0);
  const auto expectMsg = [](hawor::HandModel<S> m, const std::string& frag) {
    try {
      m.prepare();
      FAIL("no error, expected: " << frag);
    } catch (const hawor::Error& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(frag) != std::string::npos);
    }
  };
  auto m = good;
  m.vTemplate.resize(0, 3);
  expectMsg(m, "no vertices");
  m = good;
  m.parents.clear();
  expectMsg(m, "no joints");
  m = good;
  m.vTemplate(3, 1) = std::numeric_limits<S>::quiet_NaN();
  expectMsg(m, "v_template has non-finite");
  m = good;
  m.shapedirs.conservativeResize(m.shapedirs.rows() - 3, Eigen::NoChange);
  expectMsg(m, "shapedirs");
  m = good;
  m.posedirs.conservativeResize(Eigen::NoChange, 27);
  expectMsg(m, "posedirs");
  m = good;
  m.jRegressor.conservativeResize(4, Eigen::NoChange);
  expectMsg(m, "J_regressor");
  m = good;
  m.weights.conservativeResize(Eigen::NoChange, 6);
  expectMsg(m, "weights");
  m = good;
  m.faces(2, 1) = 40;
  expectMsg(m, "face 2");
  m = good;
  m.parents[0] = 0;
  expectMsg(m, "root");
  m = good;
  m.parents[2] = 3;
  expectMsg(m, "parents must precede");
  m = good;
  m.tipVertices = {41};
  expectMsg(m, "keypoint vertex");
  m = good;
  m.keypointMap = {0, 5};
  expectMsg(m, "keypoint index");
  // A generic model (5 joints, 40 vertices) runs.
  const auto out = hawor::forward(good, hand_test::randomPose(good, 2));
  CHECK(out.vertices.rows() == 40);
  CHECK(out.joints.rows() == 5);
}

TEMPLATE_TEST_CASE("hand mirror: left(mirrorPose(p)) = M right(p)", "[hand][mirror]", float, double) {
  using S = TestType;
  const auto right = hand_test::randomModel<S>();
  const auto left = hawor::mirrorHandModel(right);
  CHECK(left.isLeft);
  const Eigen::Matrix<S, 1, 3> M(S(-1), S(1), S(1));
  for (unsigned seed = 10; seed < 14; ++seed) {
    const auto p = hand_test::randomPose(right, seed, 0.8);
    const auto r = hawor::forward(right, p);
    const auto l = hawor::forward(left, hawor::mirrorPose(p));
    const hawor::Points3<S> mv = r.vertices.array().rowwise() * M.array();
    const hawor::Points3<S> mj = r.joints.array().rowwise() * M.array();
    const hawor::Points3<S> mk = r.keypoints.array().rowwise() * M.array();
    CHECK(fwdMaxAbs(l.vertices, mv) <= 8 * fwdTol<S>());
    CHECK(fwdMaxAbs(l.joints, mj) <= 8 * fwdTol<S>());
    CHECK(fwdMaxAbs(l.keypoints, mk) <= 8 * fwdTol<S>());
    // The naive "same parameters" is not the mirror image.
    const auto naive = hawor::forward(left, p);
    CHECK(fwdMaxAbs(naive.vertices, mv) > 1e-3);
  }
  // Mirroring twice is the identity.
  const auto p = hand_test::randomPose(right, 20);
  const auto pp = hawor::mirrorPose(hawor::mirrorPose(p));
  CHECK(fwdMaxAbs(pp.handPose, p.handPose) == 0.0);
  CHECK(fwdMaxAbs(pp.rot, p.rot) == 0.0);
  CHECK(fwdMaxAbs(pp.trans, p.trans) == 0.0);
  const auto back = hawor::mirrorHandModel(left);
  CHECK(fwdMaxAbs(back.posedirs, right.posedirs) == 0.0);
  CHECK((back.faces.array() == right.faces.array()).all());
}

TEMPLATE_TEST_CASE("hand mirror: axis-angle rule and the left shapedirs fix", "[hand][mirror]", float, double) {
  using S = TestType;
  // M R(w) M = R(mirrorAxisAngle(w)) for M = diag(-1, 1, 1).
  const hawor::Mat3<S> M = hawor::Vec3<S>(S(-1), S(1), S(1)).asDiagonal();
  for (const hawor::Vec3<S>& w : {hawor::Vec3<S>(S(0.3), S(-0.7), S(1.1)), hawor::Vec3<S>(S(3.0), S(0.1), S(0.2)),
                                hawor::Vec3<S>(S(1e-7), S(2e-7), S(0))}) {
    const hawor::Mat3<S> a = M * hawor::axisAngleToMatrix(w) * M;
    const hawor::Mat3<S> b = hawor::axisAngleToMatrix(hawor::mirrorAxisAngle<S>(w));
    CHECK(fwdMaxAbs(a, b) <= 4 * fwdTol<S>());
  }
  // A left model as released (shapedirs x not mirrored) equals the true mirror after the fix,
  // and the fix matters as soon as betas are non-zero.
  const auto right = hand_test::randomModel<S>(778, hawor::manoParents(), 10, true, 9);
  const auto left = hawor::mirrorHandModel(right);
  auto buggy = left;
  for (int v = 0; v < buggy.numVertices(); ++v) buggy.shapedirs.row(3 * v) = right.shapedirs.row(3 * v);
  buggy.prepare();
  const auto p = hand_test::randomPose(left, 30);
  CHECK(fwdMaxAbs(hawor::forward(buggy, p).vertices, hawor::forward(left, p).vertices) > 1e-3);
  hawor::fixLeftShapedirs(buggy);
  buggy.prepare();
  CHECK(fwdMaxAbs(buggy.shapedirs, left.shapedirs) == 0.0);
  CHECK(fwdMaxAbs(hawor::forward(buggy, p).vertices, hawor::forward(left, p).vertices) == 0.0);
  // Face winding [0,2,1].
  const hawor::Faces f = hawor::flipFaceWinding(right.faces);
  CHECK((f.col(0).array() == right.faces.col(0).array()).all());
  CHECK((f.col(1).array() == right.faces.col(2).array()).all());
  CHECK((f.col(2).array() == right.faces.col(1).array()).all());
}
