// Place recognition's parts: the binary descriptors (binary_descriptor.hpp) by their invariances
// (exact under translation and positive affine intensity changes, near under a 90° rotation of
// the image) and their distinctiveness; the matching and the place index against brute force
// written out here; the Sim(3) RANSAC (sim3_ransac.hpp) against a known similarity with outliers
// and with matches that agree only in the image (maxDepthError);
// the Sim(3) pose graph (pose_graph.hpp) against consistent poses and a least-squares answer
// solved here.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "hawor/slam/binary_descriptor.hpp"
#include "hawor/slam/place_index.hpp"
#include "hawor/slam/pose_graph.hpp"
#include "hawor/slam/sim3_ransac.hpp"

namespace {

// A textured image: smooth random blobs (a sum of Gaussians), values in [0, 255].
hawor::ImageF blobImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<std::array<double, 4>> blobs(220);
  for (auto& b : blobs) b = {U(rng) * w, U(rng) * h, 2.0 + 6.0 * U(rng), U(rng) < 0.5 ? -1.0 : 1.0};
  hawor::ImageF im;
  im.resize(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = 128.0;
      for (const auto& b : blobs) {
        const double d2 = (x - b[0]) * (x - b[0]) + (y - b[1]) * (y - b[1]);
        v += 60.0 * b[3] * std::exp(-d2 / (2.0 * b[2] * b[2]));
      }
      im.row(y)[x] = float(std::min(255.0, std::max(0.0, v)));
    }
  return im;
}

int bruteHamming(const hawor::BinaryDescriptor& a, const hawor::BinaryDescriptor& b) {
  int n = 0;
  for (int i = 0; i < 256; ++i) n += ((a.bits[std::size_t(i / 64)] >> (i % 64)) & 1u) != ((b.bits[std::size_t(i / 64)] >> (i % 64)) & 1u);
  return n;
}

}  // namespace

TEST_CASE("binary descriptors: invariances and distinctiveness", "[slam][place]") {
  const hawor::ImageF im = blobImage(160, 120, 7);
  hawor::BinaryDescriptorExtractor ex;
  ex.setImage(im);
  std::vector<std::array<int, 2>> pts;
  for (int y = 30; y <= 90; y += 12)
    for (int x = 30; x <= 130; x += 12) pts.push_back({x, y});
  std::vector<hawor::BinaryDescriptor> d(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) REQUIRE(ex.compute(float(pts[i][0]), float(pts[i][1]), d[i]));

  SECTION("border and non-finite points have none") {
    hawor::BinaryDescriptor t;
    CHECK_FALSE(ex.compute(float(hawor::BinaryDescriptorExtractor::border() - 1), 60.f, t));
    CHECK_FALSE(ex.compute(80.f, float(120 - hawor::BinaryDescriptorExtractor::border()), t));
    CHECK_FALSE(ex.compute(std::nanf(""), 60.f, t));
    CHECK(ex.compute(float(hawor::BinaryDescriptorExtractor::border()), 60.f, t));
  }
  SECTION("Hamming distance is the count of differing bits") {
    for (std::size_t i = 0; i + 1 < d.size(); ++i) CHECK(hawor::hammingDistance(d[i], d[i + 1]) == bruteHamming(d[i], d[i + 1]));
  }
  SECTION("the same descriptor after a translation and a positive affine change of intensity") {
    hawor::ImageF moved;
    moved.resize(160, 120, 1);
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) moved.row(y)[x] = 0.5f * im.row(std::min(119, y + 3))[std::min(159, x + 5)] + 40.f;
    hawor::BinaryDescriptorExtractor ex2;
    ex2.setImage(moved);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      hawor::BinaryDescriptor t;
      REQUIRE(ex2.compute(float(pts[i][0] - 5), float(pts[i][1] - 3), t));
      CHECK(hawor::hammingDistance(t, d[i]) <= 2);  // (0.5·v rounds differently only at ties)
    }
  }
  SECTION("a 90° rotation of the image: near, by the orientation") {
    // rot(x', y') = im(159 − y', x'): im turned by 90°; im's point (x, y) is rot's (y, 159 − x)
    hawor::ImageF rot;
    rot.resize(120, 160, 1);
    for (int y = 0; y < 160; ++y)
      for (int x = 0; x < 120; ++x) rot.row(y)[x] = im.row(x)[159 - y];
    hawor::BinaryDescriptorExtractor ex2;
    ex2.setImage(rot);
    std::vector<int> same, other;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      hawor::BinaryDescriptor t;
      REQUIRE(ex2.compute(float(pts[i][1]), float(159 - pts[i][0]), t));
      same.push_back(hawor::hammingDistance(t, d[i]));
      other.push_back(hawor::hammingDistance(t, d[(i + 7) % d.size()]));
    }
    std::sort(same.begin(), same.end());
    std::sort(other.begin(), other.end());
    CHECK(same[same.size() / 2] <= 40);     // the orientation's 12° steps leave some bits
    CHECK(other[other.size() / 2] >= 80);   // other points of this image: 90-odd bits
    CHECK(2 * same[same.size() / 2] < other[other.size() / 2]);
  }
}

TEST_CASE("matchBinaryDescriptors: mutual nearest, ratio and distance, against brute force", "[slam][place]") {
  std::mt19937_64 rng(3);
  std::vector<hawor::BinaryDescriptor> train(60), query;
  for (auto& t : train) t.bits = {rng(), rng(), rng(), rng()};
  // queries: noisy copies of the first 40 (k bits flipped), and 20 random ones
  for (int i = 0; i < 60; ++i) {
    hawor::BinaryDescriptor q = i < 40 ? train[std::size_t(i)] : hawor::BinaryDescriptor{{rng(), rng(), rng(), rng()}};
    for (int k = 0; k < (i < 40 ? i : 0); ++k) q.bits[std::size_t(rng() % 4)] ^= std::uint64_t(1) << (rng() % 64);
    query.push_back(q);
  }
  const auto m = hawor::matchBinaryDescriptors(query, train, 64, 0.8);
  // brute force
  std::vector<std::array<int, 3>> ref;
  for (std::size_t i = 0; i < query.size(); ++i) {
    int b1 = 999, b2 = 999, j1 = -1;
    for (std::size_t j = 0; j < train.size(); ++j) {
      const int dd = bruteHamming(query[i], train[j]);
      if (dd < b1) b2 = b1, b1 = dd, j1 = int(j);
      else if (dd < b2) b2 = dd;
    }
    if (b1 > 64 || !(b1 < 0.8 * b2)) continue;
    int best = 999, bi = -1;
    for (std::size_t k = 0; k < query.size(); ++k) {
      const int dd = bruteHamming(query[k], train[std::size_t(j1)]);
      if (dd < best) best = dd, bi = int(k);
    }
    if (bi == int(i)) ref.push_back({int(i), j1, b1});
  }
  REQUIRE(m.size() == ref.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    CHECK(m[i].query == ref[i][0]);
    CHECK(m[i].train == ref[i][1]);
    CHECK(m[i].distance == ref[i][2]);
  }
  CHECK(m.size() >= 30);  // the copies with fewer flipped bits
}

TEST_CASE("PlaceIndex: votes are the query descriptors sharing a 16-bit word, by brute force", "[slam][place]") {
  std::mt19937_64 rng(11);
  auto randomDesc = [&] { return hawor::BinaryDescriptor{{rng(), rng(), rng(), rng()}}; };
  std::vector<std::vector<hawor::BinaryDescriptor>> entries(12);
  for (auto& e : entries)
    for (int i = 0; i < 50; ++i) e.push_back(randomDesc());
  hawor::PlaceIndex index(1.0);  // no stop words
  for (std::size_t k = 0; k < entries.size(); ++k) index.add(int(k) * 2, entries[k]);  // ids need not be dense
  CHECK(index.size() == 12);
  CHECK_THROWS_AS(index.add(4, entries[0]), hawor::Error);
  // the query: descriptors of entry 5 with a few bits flipped, and random ones
  std::vector<hawor::BinaryDescriptor> q;
  for (int i = 0; i < 30; ++i) {
    hawor::BinaryDescriptor d = entries[5][std::size_t(i)];
    for (int k = 0; k < 12; ++k) d.bits[std::size_t(rng() % 4)] ^= std::uint64_t(1) << (rng() % 64);
    q.push_back(d);
  }
  for (int i = 0; i < 30; ++i) q.push_back(randomDesc());
  auto word = [](const hawor::BinaryDescriptor& d, int c) { return (d.bits[std::size_t(c / 4)] >> (16 * (c % 4))) & 0xffffu; };
  const auto cand = index.query(q, 1, [](int) { return true; });
  for (std::size_t k = 0; k < entries.size(); ++k) {
    int votes = 0;
    for (const auto& a : q) {
      bool share = false;
      for (const auto& b : entries[k])
        for (int c = 0; c < 16; ++c) share = share || word(a, c) == word(b, c);
      votes += share;
    }
    const auto it = std::find_if(cand.begin(), cand.end(), [&](const hawor::PlaceCandidate& p) { return p.entry == int(k) * 2; });
    CHECK((it == cand.end() ? 0 : it->votes) == votes);
  }
  REQUIRE(!cand.empty());
  CHECK(cand.front().entry == 10);
  CHECK(cand.front().votes >= 20);
  // the filter
  const auto none = index.query(q, 1, [](int id) { return id != 10; });
  CHECK(std::none_of(none.begin(), none.end(), [](const hawor::PlaceCandidate& p) { return p.entry == 10; }));
}

TEMPLATE_TEST_CASE("solveSim3Ransac recovers a known similarity from matches with outliers", "[slam][place]", float, double) {
  using S = TestType;
  using V3 = hawor::Vec3<S>;
  using V2 = hawor::Vec2<S>;
  hawor::PinholeCamera<S> cam{S(400), S(400), S(320), S(240)};
  // camera 2's points (its own frame, its own scale); camera 1 sees them through S_true
  const hawor::Sim3<S> truth(S(2.5), hawor::SO3<S>::exp(V3(S(0.1), S(-0.3), S(0.05))), V3(S(0.4), S(-0.2), S(0.3)));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::normal_distribution<double> N(0.0, 0.5);
  std::vector<V3> P1, P2;
  std::vector<V2> u1, u2;
  std::vector<char> wrong;
  for (int i = 0; i < 120; ++i) {
    const V3 p2(S(U(rng) * 1.5), S(U(rng)), S(3 + U(rng)));
    V3 p1 = truth * p2;
    if (!(p1.z() > S(0.5))) continue;
    V2 a = cam.project(p1) + V2(S(N(rng)), S(N(rng)));
    V2 b = cam.project(p2) + V2(S(N(rng)), S(N(rng)));
    wrong.push_back(i % 3 == 0);
    if (wrong.back()) p1 = V3(S(U(rng)), S(U(rng)), S(6 + U(rng)));  // a third wrong: another point
    P1.push_back(p1), P2.push_back(p2), u1.push_back(a), u2.push_back(b);
  }
  hawor::Sim3RansacOptions<S> o;
  o.thresholdPx = S(3);
  const auto r = hawor::solveSim3Ransac(P1, P2, u1, u2, cam, o);
  REQUIRE(r.found);
  CHECK(r.S.scale() == Approx(double(truth.scale())).epsilon(0.01));
  CHECK((r.S.rotation().inverse() * truth.rotation()).log().norm() < S(0.01));
  CHECK((r.S.translation() - truth.translation()).norm() < S(0.03));
  int wrongIn = 0, rightIn = 0, right = 0;
  for (std::size_t i = 0; i < P1.size(); ++i) {
    wrongIn += wrong[i] && r.inliers[i];
    rightIn += !wrong[i] && r.inliers[i];
    right += !wrong[i];
  }
  CHECK(wrongIn <= 2);
  CHECK(rightIn >= right * 9 / 10);
  // too few matches, and mismatched sizes
  const std::vector<V3> few(P1.begin(), P1.begin() + 5), few2(P2.begin(), P2.begin() + 5);
  const std::vector<V2> fu(u1.begin(), u1.begin() + 5), fu2(u2.begin(), u2.begin() + 5);
  CHECK_FALSE(hawor::solveSim3Ransac(few, few2, fu, fu2, cam, o).found);
  CHECK_THROWS_AS(hawor::solveSim3Ransac(P1, few2, u1, u2, cam, o), hawor::Error);
}

TEMPLATE_TEST_CASE("optimisePoseGraph: a drifted chain with a loop returns to the consistent poses", "[slam][posegraph]", float, double) {
  using S = TestType;
  using Sim = hawor::Sim3<S>;
  using V7 = hawor::Vec7<S>;
  std::mt19937 rng(9);
  std::normal_distribution<double> N(0.0, 1.0);
  auto randomSim = [&](double t, double r, double s) {
    V7 xi;
    for (int a = 0; a < 3; ++a) xi(a) = S(t * N(rng));
    for (int a = 3; a < 6; ++a) xi(a) = S(r * N(rng));
    xi(6) = S(s * N(rng));
    return Sim::exp(xi);
  };
  std::vector<Sim> truth(12);
  for (std::size_t i = 1; i < truth.size(); ++i) truth[i] = truth[i - 1] * randomSim(0.5, 0.2, 0.05);
  std::vector<hawor::PoseGraphEdge<S>> edges;
  for (int i = 0; i + 1 < 12; ++i) edges.push_back({i, i + 1, Sim(truth[std::size_t(i)].inverse() * truth[std::size_t(i + 1)]), V7::Ones()});
  edges.push_back({0, 11, Sim(truth[0].inverse() * truth[11]), V7::Ones()});
  edges.push_back({3, 8, Sim(truth[3].inverse() * truth[8]), V7::Ones()});
  // drifted start: each node off by a small random similarity (scale too)
  std::vector<Sim> nodes = truth;
  for (std::size_t i = 1; i < nodes.size(); ++i) nodes[i] = nodes[i] * randomSim(0.05, 0.03, 0.1);
  std::vector<char> fixed(12, 0);
  fixed[0] = 1;
  const hawor::PoseGraphResult r = hawor::optimisePoseGraph(nodes, edges, fixed);
  CHECK(r.finalCost < 1e-6 * std::max(r.initialCost, 1e-12) + 1e-8);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    CHECK((nodes[i].inverse() * truth[i]).log().norm() < S(2e-3));
  }
}

TEMPLATE_TEST_CASE("optimisePoseGraph: weighted scale edges give the least-squares answer", "[slam][posegraph]", float, double) {
  using S = TestType;
  using Sim = hawor::Sim3<S>;
  using V7 = hawor::Vec7<S>;
  // identity rotations, zero translations: the residual's σ is σ_j − σ_i − m, the rest 0
  const double a = std::log(2.0), b = std::log(3.0), c = std::log(4.0);
  auto scaleEdge = [](int i, int j, double m, double w) {
    return hawor::PoseGraphEdge<S>{i, j, Sim(S(std::exp(m)), hawor::SO3<S>(), hawor::Vec3<S>::Zero()), V7::Constant(S(w))};
  };
  std::vector<hawor::PoseGraphEdge<S>> edges{scaleEdge(0, 1, a, 1), scaleEdge(1, 2, b, 1), scaleEdge(0, 2, c, 4)};
  std::vector<Sim> nodes(3);
  const hawor::PoseGraphResult r = hawor::optimisePoseGraph(nodes, edges, std::vector<char>{1, 0, 0});
  // minimise (x1 − a)² + (x2 − x1 − b)² + 4 (x2 − c)²: [2 −1; −1 5] x = [a − b; b + 4c]
  const double det = 2 * 5 - 1;
  const double x1 = (5 * (a - b) + (b + 4 * c)) / det, x2 = ((a - b) + 2 * (b + 4 * c)) / det;
  CHECK(std::log(double(nodes[1].scale())) == Approx(x1).margin(1e-4));
  CHECK(std::log(double(nodes[2].scale())) == Approx(x2).margin(1e-4));
  CHECK(nodes[1].translation().norm() < S(1e-4));
  CHECK(r.finalCost < r.initialCost);
  // the gauge and bad input
  CHECK_THROWS_AS(hawor::optimisePoseGraph(nodes, edges, std::vector<char>{0, 0, 0}), hawor::Error);
  std::vector<Sim> four(4);
  CHECK_THROWS_AS(hawor::optimisePoseGraph(four, edges, std::vector<char>{1, 0, 0, 0}), hawor::Error);  // node 3 unconnected
  auto bad = edges;
  bad[0].j = 7;
  CHECK_THROWS_AS(hawor::optimisePoseGraph(nodes, bad, std::vector<char>{1, 0, 0}), hawor::Error);
}

TEMPLATE_TEST_CASE("solveSim3Ransac: maxDepthError refuses matches that agree only in the image", "[slam][place]", float, double) {
  using S = TestType;
  using V3 = hawor::Vec3<S>;
  using V2 = hawor::Vec2<S>;
  hawor::PinholeCamera<S> cam{S(400), S(400), S(320), S(240)};
  // the two cameras at one place (a head looking around): depth is invisible to reprojection
  const hawor::Sim3<S> truth(S(2), hawor::SO3<S>::exp(V3(S(0), S(0.4), S(0))), V3::Zero());
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<V3> P1, P2;
  std::vector<V2> u1, u2;
  for (int i = 0; i < 60; ++i) {
    const V3 p2(S(U(rng)), S(U(rng) * 0.7), S(3 + U(rng)));
    V3 p1 = truth * p2;
    if (!(p1.z() > S(0.5))) continue;
    u1.push_back(cam.project(p1));
    u2.push_back(cam.project(p2));
    if (i % 2 == 0) p1 *= S(1.6);  // half: the same ray, a depth 60 % off
    P1.push_back(p1), P2.push_back(p2);
  }
  hawor::Sim3RansacOptions<S> o;
  o.minInliers = 10;
  const auto plain = hawor::solveSim3Ransac(P1, P2, u1, u2, cam, o);
  REQUIRE(plain.found);
  CHECK(plain.numInliers > int(P1.size()) * 9 / 10);  // reprojection accepts the wrong depths
  o.maxDepthError = S(0.1);
  const auto checked = hawor::solveSim3Ransac(P1, P2, u1, u2, cam, o);
  REQUIRE(checked.found);
  CHECK(checked.numInliers <= int(P1.size()) / 2 + 1);
  CHECK(checked.numInliers >= int(P1.size()) / 2 - 3);
}
