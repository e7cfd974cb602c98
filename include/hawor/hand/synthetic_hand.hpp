// hawor/hand/synthetic_hand.hpp — a procedural, licence-free right hand with MANO's structure
// (16 joints with MANO's parents and joint order, 10 shape coefficients, 135 pose-corrective
// features, 5 fingertip vertices, the 21-keypoint map of docs/design.md §3), for tests and benchmarks
// when no MANO file is at hand. Not a replacement for MANO's learned shape space.
//
// Geometry (metres, rest pose, right hand): wrist joint at `origin`, fingers along −x, the index
// finger on the +z side, the palm (volar side) facing −y; realistic adult phalanx lengths with a
// slight rest curl. Vertices are rings around each bone (the ring at a joint is centred on it,
// so the joint regressor averages that ring and J_reg·T reproduces the skeleton exactly),
// fingertip vertices at the end of the distal bones, and a palm slab. LBS weights blend a bone
// with its parent near the joint. Shape directions: β0 overall size about the wrist, β1 finger
// length, β2 palm width, β3 finger thickness, β4 thumb length, β5–β9 smooth small fields. Pose
// correctives: small, deterministic, on the vertices each joint skins.
// Deterministic (fixed seed); no I/O.
#pragma once

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/portable_random.hpp"

namespace hawor {

/// The procedural hand of the file comment, prepared. `ring` vertices per ring (>= 4).
template <typename Scalar>
HandModel<Scalar> makeSyntheticHand(int ring = 8) {
  if (ring < 4) throw Error("makeSyntheticHand: ring must be >= 4");
  using V3 = Eigen::Vector3d;
  const V3 origin(0.02, 0.004, -0.003);
  // Per chain (MANO order of chains: index, middle, pinky, ring, thumb) the base joint, the
  // initial bone direction, three bone lengths and the radius.
  struct Chain {
    V3 base, dir;
    double len[3];
    double radius;
    bool thumb;
  };
  const Chain chains[5] = {
      {V3(-0.085, 0.0, 0.024), V3(-1.0, -0.05, 0.08), {0.040, 0.024, 0.021}, 0.0095, false},   // index
      {V3(-0.090, 0.0, 0.003), V3(-1.0, -0.05, 0.0), {0.045, 0.028, 0.023}, 0.0098, false},    // middle
      {V3(-0.073, 0.0, -0.033), V3(-1.0, -0.05, -0.15), {0.033, 0.020, 0.019}, 0.0085, false},  // pinky
      {V3(-0.084, 0.0, -0.016), V3(-1.0, -0.05, -0.07), {0.042, 0.027, 0.022}, 0.0092, false},  // ring
      {V3(-0.022, -0.012, 0.022), V3(-0.55, -0.25, 0.8), {0.040, 0.033, 0.027}, 0.0110, true},  // thumb
  };
  const int J = 16, B = 10;
  std::vector<V3> joint(J);
  std::vector<V3> tipPos(5);
  std::vector<V3> boneDir(J);
  joint[0] = origin;
  boneDir[0] = V3(-1, 0, 0);
  for (int c = 0; c < 5; ++c) {
    V3 p = origin + chains[c].base;
    V3 d = chains[c].dir.normalized();
    for (int s = 0; s < 3; ++s) {
      const int j = 1 + 3 * c + s;
      joint[j] = p;
      boneDir[j] = d;
      p = p + chains[c].len[s] * d;
      // Rest curl: each bone turns 0.1 rad towards the palm (−y) for the next one.
      d = (d + V3(0, -0.1, 0)).normalized();
    }
    tipPos[c] = p;
  }

  std::vector<V3> verts;
  std::vector<std::vector<std::pair<int, double>>> skin;  // per vertex (joint, weight)
  std::vector<int> chainOf;                               // −1 palm/wrist, else chain
  std::vector<double> alongChain;                         // distance from the chain's base
  std::vector<V3> axisPoint;                              // nearest bone-axis point (thickness)
  std::vector<std::vector<int>> regressorRing(J);
  std::vector<std::array<int, 3>> faces;
  const double pi = 3.14159265358979323846;
  auto add = [&](const V3& v, std::vector<std::pair<int, double>> w, int chain, double along, const V3& axis) {
    verts.push_back(v);
    skin.push_back(std::move(w));
    chainOf.push_back(chain);
    alongChain.push_back(along);
    axisPoint.push_back(axis);
    return static_cast<int>(verts.size()) - 1;
  };
  auto frameOf = [](const V3& d, V3& a, V3& b) {
    a = d.cross(std::abs(d.y()) < 0.9 ? V3(0, 1, 0) : V3(1, 0, 0)).normalized();
    b = d.cross(a);
  };
  // Wrist ring (joint 0's regressor), in the plane perpendicular to −x.
  {
    V3 a(0, 1, 0), b(0, 0, 1);
    for (int r = 0; r < 12; ++r) {
      const double th = 2 * pi * r / 12.0;
      const V3 v = origin + 0.012 * std::cos(th) * a + 0.03 * std::sin(th) * b;
      regressorRing[0].push_back(add(v, {{0, 1.0}}, -1, 0.0, origin));
    }
  }
  int tipVertex[5] = {0, 0, 0, 0, 0};
  for (int c = 0; c < 5; ++c) {
    int prevRing = -1;
    double along = 0.0;
    for (int s = 0; s < 3; ++s) {
      const int j = 1 + 3 * c + s;
      const int parent = s == 0 ? 0 : j - 1;
      const V3 d = boneDir[j];
      V3 a, b;
      frameOf(d, a, b);
      const double len = chains[c].len[s];
      for (int q = 0; q < 4; ++q) {
        const double f = q / 4.0;
        const double radius = chains[c].radius * (1.0 - 0.1 * (s + f));
        const V3 centre = joint[j] + f * len * d;
        const double wj = q == 0 ? 0.5 : (q == 1 ? 0.8 : 1.0);
        const int first = static_cast<int>(verts.size());
        for (int r = 0; r < ring; ++r) {
          const double th = 2 * pi * r / ring;
          const V3 v = centre + radius * (std::cos(th) * a + std::sin(th) * b);
          std::vector<std::pair<int, double>> w{{j, wj}};
          if (wj < 1.0) w.push_back({parent, 1.0 - wj});
          const int id = add(v, w, c, along + f * len, centre);
          if (q == 0) regressorRing[j].push_back(id);
        }
        if (prevRing >= 0) {
          for (int r = 0; r < ring; ++r) {
            const int r2 = (r + 1) % ring;
            faces.push_back({prevRing + r, prevRing + r2, first + r});
            faces.push_back({first + r, prevRing + r2, first + r2});
          }
        }
        prevRing = first;
      }
      along += len;
    }
    // Cap ring just before the tip, then the fingertip vertex (the tip keypoint).
    const int j = 3 + 3 * c;
    V3 a, b;
    frameOf(boneDir[j], a, b);
    const V3 capCentre = tipPos[c] - 0.004 * boneDir[j];
    const int first = static_cast<int>(verts.size());
    for (int r = 0; r < ring; ++r) {
      const double th = 2 * pi * r / ring;
      add(capCentre + 0.6 * chains[c].radius * (std::cos(th) * a + std::sin(th) * b), {{j, 1.0}}, c, along - 0.004,
          capCentre);
    }
    for (int r = 0; r < ring; ++r) {
      const int r2 = (r + 1) % ring;
      faces.push_back({prevRing + r, prevRing + r2, first + r});
      faces.push_back({first + r, prevRing + r2, first + r2});
    }
    tipVertex[c] = add(tipPos[c], {{j, 1.0}}, c, along, tipPos[c]);
    for (int r = 0; r < ring; ++r) faces.push_back({first + r, first + (r + 1) % ring, tipVertex[c]});
  }
  // Palm slab: a grid between the wrist and the finger bases, two layers (back and palm side).
  for (int layer = 0; layer < 2; ++layer) {
    const double y = layer == 0 ? 0.011 : -0.013;
    for (int ix = 0; ix < 6; ++ix) {
      for (int iz = 0; iz < 5; ++iz) {
        const double fx = (ix + 0.5) / 6.0, fz = iz / 4.0;
        const V3 v = origin + V3(-0.082 * fx, y, 0.028 - 0.058 * fz);
        // Blend towards the nearest finger base near the knuckles.
        int nearest = 1;
        double best = 1e9;
        for (int c = 0; c < 4; ++c) {
          const double dz = std::abs(joint[1 + 3 * c].z() - v.z());
          if (dz < best) {
            best = dz;
            nearest = 1 + 3 * c;
          }
        }
        const double wf = fx > 0.75 ? 0.4 * (fx - 0.75) / 0.25 : 0.0;
        std::vector<std::pair<int, double>> w{{0, 1.0 - wf}};
        if (wf > 0.0) w.push_back({nearest, wf});
        add(v, w, -1, 0.0, V3(v.x(), origin.y(), v.z()));
      }
    }
  }

  const int V = static_cast<int>(verts.size());
  HandModel<Scalar> m;
  m.parents = manoParents();
  m.vTemplate.resize(V, 3);
  for (int v = 0; v < V; ++v) m.vTemplate.row(v) = verts[static_cast<std::size_t>(v)].transpose().cast<Scalar>();
  m.weights = MatX<Scalar>::Zero(V, J);
  for (int v = 0; v < V; ++v)
    for (const auto& jw : skin[static_cast<std::size_t>(v)]) m.weights(v, jw.first) += Scalar(jw.second);
  m.jRegressor = MatX<Scalar>::Zero(J, V);
  for (int j = 0; j < J; ++j) {
    const auto& r = regressorRing[static_cast<std::size_t>(j)];
    for (int id : r) m.jRegressor(j, id) = Scalar(1.0 / static_cast<double>(r.size()));
  }
  m.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) m.faces(static_cast<Eigen::Index>(f), k) = faces[f][static_cast<std::size_t>(k)];

  // Shape directions (file comment).
  std::mt19937 rng(12345);
  auto gauss = [&](std::mt19937& r) { return standardNormal(r); };
  // Three variates in a fixed order (argument evaluation order is unspecified in C++).
  auto gauss3 = [&](std::mt19937& r) {
    const double a = gauss(r), b = gauss(r), c = gauss(r);
    return V3(a, b, c);
  };
  auto uni = [&](std::mt19937& r) { return 2 * pi * uniform01(r); };
  V3 freq[5][3];
  double phase[5][3];
  for (int k = 0; k < 5; ++k)
    for (int c = 0; c < 3; ++c) {
      freq[k][c] = gauss3(rng) * 25.0;
      phase[k][c] = uni(rng);
    }
  m.shapedirs = MatX<Scalar>::Zero(3 * V, B);
  for (int v = 0; v < V; ++v) {
    const std::size_t sv = static_cast<std::size_t>(v);
    const V3 p = verts[sv];
    const int c = chainOf[sv];
    std::array<V3, 10> d;
    d.fill(V3::Zero());
    d[0] = 0.04 * (p - origin);
    if (c >= 0 && c < 4) d[1] = 0.05 * alongChain[sv] * chains[c].dir.normalized();
    d[2] = V3(0, 0, 0.05 * (p.z() - origin.z()));
    if (c >= 0) d[3] = 0.08 * (p - axisPoint[sv]);
    if (c == 4) d[4] = 0.06 * alongChain[sv] * chains[4].dir.normalized();
    for (int k = 0; k < 5; ++k)
      for (int a = 0; a < 3; ++a) d[5 + static_cast<std::size_t>(k)](a) = 0.0015 * std::sin(freq[k][a].dot(p) + phase[k][a]);
    for (int k = 0; k < B; ++k)
      for (int a = 0; a < 3; ++a) m.shapedirs(3 * v + a, k) = Scalar(d[static_cast<std::size_t>(k)](a));
  }
  // Pose correctives: each feature of joint j displaces the vertices j skins along a fixed
  // random direction, scaled by the skinning weight (≤ 2 mm per unit feature).
  m.posedirs = MatX<Scalar>::Zero(3 * V, 9 * (J - 1));
  for (int j = 1; j < J; ++j) {
    for (int f = 0; f < 9; ++f) {
      const V3 dir = gauss3(rng).normalized() * 0.002;
      for (int v = 0; v < V; ++v) {
        const double w = static_cast<double>(m.weights(v, j));
        if (w == 0.0) continue;
        for (int a = 0; a < 3; ++a) m.posedirs(3 * v + a, 9 * (j - 1) + f) = Scalar(w * dir(a));
      }
    }
  }
  // MANO's tip order: thumb, index, middle, ring, pinky (chains 4, 0, 1, 3, 2).
  m.tipVertices = {tipVertex[4], tipVertex[0], tipVertex[1], tipVertex[3], tipVertex[2]};
  m.keypointMap = manoKeypointMap();
  m.isLeft = false;
  m.prepare();
  return m;
}

}  // namespace hawor
