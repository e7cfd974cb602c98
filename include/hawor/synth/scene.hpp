// hawor/synth/scene.hpp — the textured indoor scene of the synthetic sequences: a room with a
// table, shelves, a sideboard, a door, posters and objects, as one triangle mesh with per-vertex
// texture coordinates and per-face materials.
//
// Room frame (the scene's own frame, not the output world frame): metres, x and y horizontal,
// z up (gravity along −z), floor at z = 0, the room spans [0, 6] × [0, 5] × [0, 2.6].
// Fixed layout (so that the camera paths of trajectory.hpp stay clear of the furniture):
//   table       top x ∈ [2.2, 3.8], y ∈ [1.8, 2.7], z = 0.75, objects on it (random per seed)
//   chairs      at both short ends of the table
//   shelf       x ∈ [0.8, 2.6] against the wall y = 5, 2 m high, 5 boards of books and boxes
//   sideboard   x ∈ [5.55, 6], y ∈ [1.2, 3.6], 0.9 m high, objects on top
//   walls       y = 0 bricks with two posters; x = 6 tiles below 1.3 m and a poster; y = 5 and
//               x = 0 plain (the low-texture walls), x = 0 with a panelled wooden door, a light
//               switch, a radiator and one small picture,
//               y = 5 with a poster and a calendar; plain ceiling with a lamp; plank floor; a rug
// What varies with the seed: every texture, colours, the objects on the table, the books and
// boxes on the shelf and sideboard, the poster contents.
// Texture coordinates are metres along each surface (from a random origin per object), turned
// into texels by the material's texelsPerMetre. Lighting is fixed in the room: an ambient term
// and two directional lights (Lambert), see IndoorScene::shade().
// Thread-safety: a built scene is read-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/render/rasterizer.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/texture.hpp"

namespace hawor {
namespace synth {

/// How a face is coloured: texture × tint, with texture coordinates in metres scaled by
/// texelsPerMetre (texels of the texture's level 0 per metre of surface).
struct SceneMaterial {
  int texture = 0;
  Rgb tint{1.0f, 1.0f, 1.0f};
  float texelsPerMetre = 256.0f;
};

/// Fixed places of the room that the camera paths use (room frame, metres).
template <typename Scalar>
struct RoomLayout {
  Vec3<Scalar> size{Scalar(6), Scalar(5), Scalar(2.6)};
  Vec2<Scalar> tableMin{Scalar(2.2), Scalar(1.8)};  ///< table top, x/y extent
  Vec2<Scalar> tableMax{Scalar(3.8), Scalar(2.7)};
  Scalar tableHeight = Scalar(0.75);
  /// Corners of a walking loop around the table, ≥ 0.6 m from walls and furniture.
  std::vector<Vec2<Scalar>> walkLoop;
  /// Open floor spots for standing and looking around (≥ 0.7 m from everything).
  std::vector<Vec2<Scalar>> standSpots;
};

template <typename Scalar>
struct IndoorScene {
  Points3<Scalar> vertices;          ///< (V,3) room frame
  TriangleList faces;                ///< (F,3)
  std::vector<float> uv;             ///< 2V: metres along the surface
  std::vector<int> faceMaterial;     ///< (F) index into materials
  std::vector<SceneMaterial> materials;
  std::vector<Texture> textures;
  RoomLayout<Scalar> layout;
  Vec3<Scalar> lightDir1 = Vec3<Scalar>(Scalar(0.3), Scalar(0.45), Scalar(1)).normalized();  ///< towards the light
  Vec3<Scalar> lightDir2 = Vec3<Scalar>(Scalar(-0.6), Scalar(-0.35), Scalar(0.45)).normalized();
  float ambient = 0.42f, light1 = 0.55f, light2 = 0.2f;

  int numFaces() const { return static_cast<int>(faces.rows()); }
  int numVertices() const { return static_cast<int>(vertices.rows()); }

  /// Lambert shading factor of a unit normal n (room frame): ambient + Σ I_k·max(0, n·l_k).
  float shade(const Vec3<Scalar>& n) const {
    const float d1 = static_cast<float>(n.dot(lightDir1)), d2 = static_cast<float>(n.dot(lightDir2));
    return ambient + light1 * (d1 > 0.0f ? d1 : 0.0f) + light2 * (d2 > 0.0f ? d2 : 0.0f);
  }

  /// Unit normal of face f as wound, (p1 − p0) × (p2 − p0) normalised (room frame).
  Vec3<Scalar> faceNormal(int f) const {
    const Vec3<Scalar> p0 = vertices.row(faces(f, 0)).transpose(), p1 = vertices.row(faces(f, 1)).transpose(),
                       p2 = vertices.row(faces(f, 2)).transpose();
    const Vec3<Scalar> n = (p1 - p0).cross(p2 - p0);
    const Scalar len = n.norm();
    return len > Scalar(0) ? Vec3<Scalar>(n / len) : Vec3<Scalar>::UnitZ();
  }
};

namespace scene_detail {

/// Accumulates quads, boxes, cylinders and spheres into an IndoorScene.
template <typename Scalar>
class SceneBuilder {
 public:
  using V3 = Vec3<Scalar>;
  explicit SceneBuilder(IndoorScene<Scalar>& s) : s_(s) {}

  int material(int texture, const Rgb& tint, float texelsPerMetre) {
    s_.materials.push_back({texture, tint, texelsPerMetre});
    return static_cast<int>(s_.materials.size()) - 1;
  }

  /// Quad p0 p1 p2 p3 (a parallelogram or close to one) as two triangles; u along p0→p1 and v
  /// along the part of p0→p3 orthogonal to it, in metres, plus (u0, v0).
  void quad(const V3& p0, const V3& p1, const V3& p2, const V3& p3, int mat, float u0 = 0, float v0 = 0) {
    const V3 e1 = (p1 - p0).normalized();
    V3 e2 = p3 - p0;
    e2 = (e2 - e2.dot(e1) * e1).normalized();
    const int base = static_cast<int>(verts_.size());
    for (const V3* p : {&p0, &p1, &p2, &p3}) {
      verts_.push_back(*p);
      uv_.push_back(u0 + static_cast<float>((*p - p0).dot(e1)));
      uv_.push_back(v0 + static_cast<float>((*p - p0).dot(e2)));
    }
    tri(base, base + 1, base + 2, mat);
    tri(base, base + 2, base + 3, mat);
  }

  /// Axis-aligned box [lo, hi] turned by (c, s) = (cos, sin) of a yaw about its vertical axis
  /// through the centre; `side` for the four sides, `top` and `bottom` materials (−1: no face).
  void box(const V3& lo, const V3& hi, int side, int top, int bottom, Scalar c = Scalar(1), Scalar s = Scalar(0),
           float u0 = 0, float v0 = 0) {
    const V3 ctr = (lo + hi) / Scalar(2);
    const V3 h = (hi - lo) / Scalar(2);
    auto P = [&](int sx, int sy, int sz) {
      const Scalar x = h.x() * Scalar(sx), y = h.y() * Scalar(sy);
      return V3(ctr.x() + c * x - s * y, ctr.y() + s * x + c * y, ctr.z() + h.z() * Scalar(sz));
    };
    // Sides (outward, counter-clockwise seen from outside), top, bottom.
    quad(P(-1, -1, -1), P(1, -1, -1), P(1, -1, 1), P(-1, -1, 1), side, u0, v0);
    quad(P(1, -1, -1), P(1, 1, -1), P(1, 1, 1), P(1, -1, 1), side, u0 + 1.3f, v0);
    quad(P(1, 1, -1), P(-1, 1, -1), P(-1, 1, 1), P(1, 1, 1), side, u0 + 2.1f, v0 + 0.4f);
    quad(P(-1, 1, -1), P(-1, -1, -1), P(-1, -1, 1), P(-1, 1, 1), side, u0 + 0.7f, v0 + 0.9f);
    if (top >= 0) quad(P(-1, -1, 1), P(1, -1, 1), P(1, 1, 1), P(-1, 1, 1), top, u0, v0);
    if (bottom >= 0) quad(P(-1, 1, -1), P(1, 1, -1), P(1, -1, -1), P(-1, -1, -1), bottom, u0, v0);
  }

  /// Vertical cylinder: base centre, radius, height, `n` segments, side / top / bottom materials.
  void cylinder(const V3& base, Scalar r, Scalar height, int n, int side, int top, int bottom, float u0 = 0) {
    std::vector<Scalar> cs(static_cast<std::size_t>(n) + 1), sn(static_cast<std::size_t>(n) + 1);
    for (int i = 0; i <= n; ++i) {
      const double a = 2.0 * 3.14159265358979323846 * i / n;
      cs[static_cast<std::size_t>(i)] = i == n ? Scalar(1) : Scalar(std::cos(a));
      sn[static_cast<std::size_t>(i)] = i == n ? Scalar(0) : Scalar(std::sin(a));
    }
    const float arc = static_cast<float>(2.0 * 3.14159265358979323846 * static_cast<double>(r) / n);
    for (int i = 0; i < n; ++i) {
      const std::size_t a = static_cast<std::size_t>(i), b = a + 1;
      const V3 p0(base.x() + r * cs[a], base.y() + r * sn[a], base.z());
      const V3 p1(base.x() + r * cs[b], base.y() + r * sn[b], base.z());
      const int k = static_cast<int>(verts_.size());
      verts_.push_back(p0);
      verts_.push_back(p1);
      verts_.push_back(V3(p1.x(), p1.y(), base.z() + height));
      verts_.push_back(V3(p0.x(), p0.y(), base.z() + height));
      const float ua = u0 + arc * static_cast<float>(i), ub = ua + arc, h = static_cast<float>(height);
      const float uvs[8] = {ua, 0, ub, 0, ub, h, ua, h};
      uv_.insert(uv_.end(), uvs, uvs + 8);
      tri(k, k + 1, k + 2, side);
      tri(k, k + 2, k + 3, side);
    }
    for (int capIdx = 0; capIdx < 2; ++capIdx) {
      const int mat = capIdx == 0 ? top : bottom;
      if (mat < 0) continue;
      const Scalar z = capIdx == 0 ? base.z() + height : base.z();
      const int c = static_cast<int>(verts_.size());
      verts_.push_back(V3(base.x(), base.y(), z));
      uv_.push_back(u0 + static_cast<float>(r));
      uv_.push_back(static_cast<float>(r));
      for (int i = 0; i < n; ++i) {
        const std::size_t a = static_cast<std::size_t>(i);
        verts_.push_back(V3(base.x() + r * cs[a], base.y() + r * sn[a], z));
        uv_.push_back(u0 + static_cast<float>(r * (Scalar(1) + cs[a])));
        uv_.push_back(static_cast<float>(r * (Scalar(1) + sn[a])));
      }
      for (int i = 0; i < n; ++i) {
        const int a = c + 1 + i, b = c + 1 + (i + 1) % n;
        if (capIdx == 0) {
          tri(c, a, b, mat);
        } else {
          tri(c, b, a, mat);
        }
      }
    }
  }

  /// Sphere (latitude-longitude, `rings` × `segments`), texture coordinates by arc length.
  void sphere(const V3& centre, Scalar r, int rings, int segments, int mat) {
    const int base = static_cast<int>(verts_.size());
    const double pi = 3.14159265358979323846;
    for (int i = 0; i <= rings; ++i) {
      const double th = pi * i / rings;
      for (int j = 0; j <= segments; ++j) {
        const double ph = 2.0 * pi * j / segments;
        const Scalar st = Scalar(std::sin(th)), ct = Scalar(std::cos(th));
        verts_.push_back(V3(centre.x() + r * st * Scalar(std::cos(ph)), centre.y() + r * st * Scalar(std::sin(ph)),
                            centre.z() + r * ct));
        uv_.push_back(static_cast<float>(static_cast<double>(r) * ph));
        uv_.push_back(static_cast<float>(static_cast<double>(r) * th));
      }
    }
    for (int i = 0; i < rings; ++i) {
      for (int j = 0; j < segments; ++j) {
        const int a = base + i * (segments + 1) + j, b = a + segments + 1;
        if (i > 0) tri(a, a + 1, b, mat);
        if (i < rings - 1) tri(a + 1, b + 1, b, mat);
      }
    }
  }

  void finish() {
    s_.vertices.resize(static_cast<Eigen::Index>(verts_.size()), 3);
    for (std::size_t i = 0; i < verts_.size(); ++i) s_.vertices.row(static_cast<Eigen::Index>(i)) = verts_[i].transpose();
    s_.faces.resize(static_cast<Eigen::Index>(faces_.size() / 3), 3);
    for (std::size_t i = 0; i < faces_.size(); ++i) s_.faces.data()[i] = faces_[i];
    s_.uv = uv_;
    s_.faceMaterial = mats_;
  }

 private:
  void tri(int a, int b, int c, int mat) {
    faces_.push_back(a);
    faces_.push_back(b);
    faces_.push_back(c);
    mats_.push_back(mat);
  }

  IndoorScene<Scalar>& s_;
  std::vector<V3> verts_;
  std::vector<float> uv_;
  std::vector<int> faces_;
  std::vector<int> mats_;
};

}  // namespace scene_detail

/// Texture resolution of the scene: 1 = full (floors and walls 512², details 256²), 2 = half
/// (faster to build, for small test images).
struct SceneOptions {
  int textureDivisor = 1;
};

/// Builds the room of the file comment for a seed.
template <typename Scalar>
IndoorScene<Scalar> makeIndoorScene(std::uint64_t seed, const SceneOptions& options = SceneOptions()) {
  if (options.textureDivisor != 1 && options.textureDivisor != 2 && options.textureDivisor != 4) {
    throw Error("makeIndoorScene: textureDivisor must be 1, 2 or 4");
  }
  using V3 = Vec3<Scalar>;
  using S = Scalar;
  IndoorScene<Scalar> scene;
  SynthRng rng(seed, 0x5CE7E);
  const int big = 512 / options.textureDivisor, small = 256 / options.textureDivisor;
  const float texScale = 1.0f / static_cast<float>(options.textureDivisor);
  auto tex = [&](Texture t) {
    scene.textures.push_back(std::move(t));
    return static_cast<int>(scene.textures.size()) - 1;
  };
  // Every random draw in a statement of its own: function arguments are evaluated in an
  // unspecified order (GCC and Clang differ), so two draws in one call would not be portable.
  auto h = [&]() { return rng.bits(); };
  // A colour near `base` from one draw.
  auto jitter = [&](const Rgb& base, float spread) {
    const std::uint32_t k = h();
    return jitterColour(base, spread, k);
  };
  // Textures.
  const Rgb cPlainA = jitter(Rgb(205, 200, 188), 0.05f);
  const int tPlainA = tex(plainTexture(small, cPlainA, 0.05f, h()));
  const Rgb cPlainB = jitter(Rgb(170, 185, 195), 0.08f);
  const int tPlainB = tex(plainTexture(small, cPlainB, 0.05f, h()));
  const int tCeiling = tex(plainTexture(small, Rgb(225, 225, 220), 0.03f, h()));
  const Rgb cBricks = jitter(Rgb(150, 75, 55), 0.12f);
  const int tBricks = tex(bricksTexture(big, cBricks, Rgb(190, 185, 175), h()));
  const Rgb cTiles = jitter(Rgb(200, 205, 200), 0.06f);
  const int tTiles = tex(tilesTexture(big, cTiles, Rgb(120, 120, 115), h()));
  const Rgb cPlanks = jitter(Rgb(160, 110, 70), 0.12f);
  const int tPlanks = tex(planksTexture(big, cPlanks, h()));
  const Rgb cWood = jitter(Rgb(170, 120, 75), 0.1f);
  const int tWood = tex(woodTexture(big, cWood, h()));
  const int tClutterA = tex(clutterTexture(big, 90, h()));
  const int tClutterB = tex(clutterTexture(small, 50, h()));
  const int tPaper = tex(paperTexture(small, h()));
  const int tRug = tex(rugTexture(big, h()));
  const int tStripes = tex(stripesTexture(small, h()));
  const int tMottled = tex(mottledTexture(small, Rgb(200, 200, 200), h()));

  scene_detail::SceneBuilder<Scalar> b(scene);
  const Rgb white(1, 1, 1);
  const float tpm = texScale;  // texels per metre scale for the resolution option
  const int mPlainA = b.material(tPlainA, white, 100 * tpm);
  const int mPlainB = b.material(tPlainB, white, 100 * tpm);
  const int mCeiling = b.material(tCeiling, white, 100 * tpm);
  const int mBricks = b.material(tBricks, white, 256 * tpm);
  const int mTiles = b.material(tTiles, white, 340 * tpm);
  const int mFloor = b.material(tPlanks, white, 300 * tpm);
  const int mWood = b.material(tWood, white, 330 * tpm);
  const int mWoodDark = b.material(tWood, Rgb(0.65f, 0.6f, 0.6f), 400 * tpm);
  const int mRug = b.material(tRug, white, 260 * tpm);
  const int mPosterA = b.material(tClutterA, white, 600 * tpm);
  const int mPosterB = b.material(tClutterB, white, 400 * tpm);
  const int mPaper = b.material(tPaper, white, 900 * tpm);
  const int mDoor = b.material(tWood, Rgb(0.9f, 0.85f, 0.8f), 250 * tpm);
  const int mDoorPanel = b.material(tWood, Rgb(0.75f, 0.68f, 0.62f), 300 * tpm);
  const int mSwitch = b.material(tCeiling, Rgb(0.95f, 0.95f, 0.95f), 100 * tpm);
  const int mRadiator = b.material(tCeiling, Rgb(0.9f, 0.9f, 0.92f), 100 * tpm);
  const int mFrame = b.material(tWood, Rgb(0.5f, 0.45f, 0.45f), 500 * tpm);
  const int mLamp = b.material(tCeiling, Rgb(1.05f, 1.05f, 1.0f), 100 * tpm);

  const RoomLayout<Scalar> L;
  const S X = L.size.x(), Y = L.size.y(), Z = L.size.z();
  // Room: floor, ceiling, four walls (as seen from inside).
  b.quad(V3(0, 0, 0), V3(X, 0, 0), V3(X, Y, 0), V3(0, Y, 0), mFloor);
  b.quad(V3(0, 0, Z), V3(0, Y, Z), V3(X, Y, Z), V3(X, 0, Z), mCeiling);
  b.quad(V3(0, 0, 0), V3(0, 0, Z), V3(X, 0, Z), V3(X, 0, 0), mBricks);          // y = 0
  b.quad(V3(X, 0, 0), V3(X, 0, S(1.3)), V3(X, Y, S(1.3)), V3(X, Y, 0), mTiles);  // x = 6, lower
  b.quad(V3(X, 0, S(1.3)), V3(X, 0, Z), V3(X, Y, Z), V3(X, Y, S(1.3)), mPlainB);  // x = 6, upper
  b.quad(V3(X, Y, 0), V3(X, Y, Z), V3(0, Y, Z), V3(0, Y, 0), mPlainB);          // y = 5
  b.quad(V3(0, Y, 0), V3(0, Y, Z), V3(0, 0, Z), V3(0, 0, 0), mPlainA);          // x = 0
  // Lamp on the ceiling, rug under the table.
  b.box(V3(S(2.7), S(2.0), Z - S(0.06)), V3(S(3.3), S(2.5), Z), mLamp, -1, mLamp);
  b.quad(V3(S(1.7), S(1.2), S(0.004)), V3(S(4.3), S(1.2), S(0.004)), V3(S(4.3), S(3.3), S(0.004)),
         V3(S(1.7), S(3.3), S(0.004)), mRug);
  // Posters and pictures (thin boxes on the walls).
  auto poster = [&](const V3& lo, const V3& hi, int mat) {
    b.box(lo, hi, mFrame, mFrame, mFrame);
    // The printed face: the side facing into the room, from a random texture origin.
    const float pu = static_cast<float>(rng.uniform(0, 3));
    const float pv = static_cast<float>(rng.uniform(0, 3));
    const S eps = S(0.001);
    if (hi.y() - lo.y() < S(0.05)) {
      const S y = lo.y() < Y / 2 ? hi.y() + eps : lo.y() - eps;
      const S m = S(0.02);
      if (lo.y() < Y / 2) {
        b.quad(V3(lo.x() + m, y, lo.z() + m), V3(hi.x() - m, y, lo.z() + m), V3(hi.x() - m, y, hi.z() - m),
               V3(lo.x() + m, y, hi.z() - m), mat, pu, pv);
      } else {
        b.quad(V3(hi.x() - m, y, lo.z() + m), V3(lo.x() + m, y, lo.z() + m), V3(lo.x() + m, y, hi.z() - m),
               V3(hi.x() - m, y, hi.z() - m), mat, pu, pv);
      }
    } else {
      const S x = lo.x() < X / 2 ? hi.x() + eps : lo.x() - eps;
      const S m = S(0.02);
      if (lo.x() < X / 2) {
        b.quad(V3(x, hi.y() - m, lo.z() + m), V3(x, lo.y() + m, lo.z() + m), V3(x, lo.y() + m, hi.z() - m),
               V3(x, hi.y() - m, hi.z() - m), mat, pu, pv);
      } else {
        b.quad(V3(x, lo.y() + m, lo.z() + m), V3(x, hi.y() - m, lo.z() + m), V3(x, hi.y() - m, hi.z() - m),
               V3(x, lo.y() + m, hi.z() - m), mat, pu, pv);
      }
    }
  };
  poster(V3(S(1.0), 0, S(1.0)), V3(S(2.1), S(0.02), S(1.8)), mPosterA);
  poster(V3(S(3.6), 0, S(0.9)), V3(S(4.4), S(0.02), S(1.9)), mPosterB);
  poster(V3(X - S(0.02), S(3.9), S(1.45)), V3(X, S(4.7), S(2.1)), mPosterB);
  poster(V3(S(3.4), Y - S(0.02), S(1.0)), V3(S(4.6), Y, S(1.8)), mPosterA);
  poster(V3(S(4.9), Y - S(0.02), S(1.2)), V3(S(5.3), Y, S(1.75)), mPaper);  // calendar
  poster(V3(0, S(1.6), S(1.3)), V3(S(0.02), S(2.0), S(1.6)), mPosterB);     // small picture, plain wall
  // Wooden panelled door with frame on the plain wall x = 0, a light switch, and a radiator
  // under the picture (the wall itself stays plain: the low-texture wall of the room).
  b.box(V3(0, S(3.4), 0), V3(S(0.04), S(4.3), S(2.05)), mDoor, mFrame, -1);
  for (int k = 0; k < 4; ++k) {
    const S y0 = S(3.5) + S(0.37) * S(k % 2), z0 = S(0.15) + S(1.0) * S(k / 2);
    b.box(V3(S(0.04), y0, z0), V3(S(0.055), y0 + S(0.33), z0 + S(0.8)), mDoorPanel, mDoorPanel, mDoorPanel);
  }
  b.box(V3(0, S(3.1), S(1.05)), V3(S(0.02), S(3.18), S(1.15)), mSwitch, mSwitch, mSwitch);
  for (int k = 0; k < 12; ++k) {
    const S y0 = S(1.35) + S(0.075) * S(k);
    b.box(V3(S(0.03), y0, S(0.15)), V3(S(0.1), y0 + S(0.05), S(0.75)), mRadiator, mRadiator, mRadiator);
  }
  b.box(V3(0, S(3.33), 0), V3(S(0.06), S(3.4), S(2.12)), mFrame, mFrame, -1);
  b.box(V3(0, S(4.3), 0), V3(S(0.06), S(4.37), S(2.12)), mFrame, mFrame, -1);
  b.box(V3(0, S(3.33), S(2.05)), V3(S(0.06), S(4.37), S(2.12)), mFrame, mFrame, -1);
  b.box(V3(S(0.04), S(4.15), S(0.98)), V3(S(0.09), S(4.22), S(1.02)), mFrame, mFrame, mFrame);  // handle

  // Table with legs.
  const S tz = L.tableHeight;
  b.box(V3(L.tableMin.x(), L.tableMin.y(), tz - S(0.04)), V3(L.tableMax.x(), L.tableMax.y(), tz), mWoodDark, mWood,
        mWoodDark);
  for (int i = 0; i < 4; ++i) {
    const S x = i % 2 ? L.tableMax.x() - S(0.08) : L.tableMin.x() + S(0.03);
    const S y = i / 2 ? L.tableMax.y() - S(0.08) : L.tableMin.y() + S(0.03);
    b.box(V3(x, y, 0), V3(x + S(0.05), y + S(0.05), tz - S(0.04)), mWoodDark, -1, -1);
  }
  // Chairs at the short ends.
  const int mChair = b.material(tMottled, jitter(Rgb(0.5f, 0.35f, 0.25f), 0.2f), 300 * tpm);
  for (int i = 0; i < 2; ++i) {
    const S x0 = i == 0 ? S(1.62) : S(3.93);
    b.box(V3(x0, S(2.0), S(0.42)), V3(x0 + S(0.45), S(2.45), S(0.47)), mChair, mChair, mChair);
    const S bx = i == 0 ? x0 : x0 + S(0.41);
    b.box(V3(bx, S(2.0), S(0.47)), V3(bx + S(0.04), S(2.45), S(0.92)), mChair, mChair, mChair);
    for (int k = 0; k < 4; ++k) {
      const S lx = k % 2 ? x0 + S(0.41) : x0, ly = k / 2 ? S(2.41) : S(2.0);
      b.box(V3(lx, ly, 0), V3(lx + S(0.04), ly + S(0.04), S(0.42)), mChair, -1, -1);
    }
  }

  // Random objects standing on a rectangle [x0, x1] × [y0, y1] at height z (non-overlapping
  // footprints, rejection sampling).
  struct Foot {
    S x, y, r;
  };
  auto placeObjects = [&](S x0, S x1, S y0, S y1, S z, int count, bool allowTall) {
    std::vector<Foot> feet;
    for (int n = 0, tries = 0; n < count && tries < 400; ++tries) {
      const int kind = rng.index(allowTall ? 8 : 6);
      // Footprint radius per kind (metres).
      static const double radius[8] = {0.13, 0.15, 0.05, 0.13, 0.05, 0.17, 0.06, 0.045};
      const S r = S(radius[kind]);
      const S x = S(rng.uniform(static_cast<double>(x0 + r), static_cast<double>(x1 - r)));
      const S y = S(rng.uniform(static_cast<double>(y0 + r), static_cast<double>(y1 - r)));
      bool clear = x1 - x0 > 2 * r && y1 - y0 > 2 * r;
      for (const Foot& f : feet) clear = clear && (x - f.x) * (x - f.x) + (y - f.y) * (y - f.y) > (r + f.r) * (r + f.r);
      if (!clear) continue;
      feet.push_back({x, y, r});
      ++n;
      // A random yaw as a unit vector (no trig needed).
      const double dx = rng.uniform(-1, 1);
      const double dy = rng.uniform(-1, 1);
      Vec2<Scalar> d = Vec2<Scalar>(S(dx), S(dy));
      if (d.norm() < S(1e-3)) d = Vec2<Scalar>(1, 0);
      d.normalize();
      const S c = d.x(), s = d.y();
      const float u0 = static_cast<float>(rng.uniform(0, 5)), v0 = static_cast<float>(rng.uniform(0, 5));
      switch (kind) {
        case 0: {  // book lying flat: cover print, page-coloured sides
          const int cover = b.material(tClutterB, jitter(Rgb(1, 1, 1), 0.1f), 800 * tpm);
          const int pages = b.material(tStripes, Rgb(0.95f, 0.92f, 0.85f), 1200 * tpm);
          const S w = S(rng.uniform(0.14, 0.2)), l = S(rng.uniform(0.2, 0.26)), t = S(rng.uniform(0.02, 0.045));
          b.box(V3(x - w / 2, y - l / 2, z), V3(x + w / 2, y + l / 2, z + t), pages, cover, cover, c, s, u0, v0);
          break;
        }
        case 1: {  // sheets of paper
          const S w = S(0.21), l = S(0.297);
          b.box(V3(x - w / 2, y - l / 2, z), V3(x + w / 2, y + l / 2, z + S(0.003)), mPaper, mPaper, -1, c, s, 0, 0);
          break;
        }
        case 2: {  // mug
          const Rgb base = paletteColour(h()) * (1.0f / 200.0f);
          const int glaze = b.material(tMottled, jitter(base, 0.1f), 700 * tpm);
          b.cylinder(V3(x, y, z), S(0.04), S(rng.uniform(0.085, 0.105)), 14, glaze, glaze, -1, u0);
          break;
        }
        case 3: {  // plate
          const int glaze = b.material(tMottled, Rgb(1.05f, 1.05f, 1.0f), 500 * tpm);
          b.cylinder(V3(x, y, z), S(rng.uniform(0.1, 0.125)), S(0.016), 24, glaze, glaze, -1, u0);
          break;
        }
        case 4: {  // fruit
          const std::uint32_t pick = h();
          const Rgb base = paletteColour(pick % 4 == 0 ? 4 : pick / 4) * (1.0f / 200.0f);
          const int skin = b.material(tMottled, jitter(base, 0.15f), 900 * tpm);
          const S r0 = S(rng.uniform(0.033, 0.045));
          b.sphere(V3(x, y, z + r0), r0, 8, 12, skin);
          break;
        }
        case 5: {  // tray / placemat with a pattern
          const int mat = b.material(tRug, jitter(Rgb(1, 1, 1), 0.1f), 900 * tpm);
          b.box(V3(x - S(0.17), y - S(0.12), z), V3(x + S(0.17), y + S(0.12), z + S(0.006)), mat, mat, -1, c, s, u0, v0);
          break;
        }
        case 6: {  // packaging box standing up
          const int print = b.material(rng.chance(0.5) ? tClutterA : tClutterB, white, 900 * tpm);  // one draw
          const S w = S(rng.uniform(0.06, 0.09)), l = S(rng.uniform(0.12, 0.19)), t = S(rng.uniform(0.18, 0.3));
          b.box(V3(x - w / 2, y - l / 2, z), V3(x + w / 2, y + l / 2, z + t), print, print, print, c, s, u0, v0);
          break;
        }
        default: {  // bottle with a label
          const int glass = b.material(tMottled, jitter(Rgb(0.35f, 0.6f, 0.4f), 0.3f), 600 * tpm);
          const int label = b.material(tClutterB, white, 900 * tpm);
          const S hgt = S(rng.uniform(0.18, 0.24));
          b.cylinder(V3(x, y, z), S(0.035), hgt * S(0.3), 12, glass, -1, -1, u0);
          b.cylinder(V3(x, y, z + hgt * S(0.3)), S(0.0352), hgt * S(0.4), 12, label, -1, -1, u0);
          b.cylinder(V3(x, y, z + hgt * S(0.7)), S(0.035), hgt * S(0.3), 12, glass, glass, -1, u0);
          b.cylinder(V3(x, y, z + hgt), S(0.013), S(0.06), 8, glass, glass, -1, u0);
          break;
        }
      }
    }
  };
  placeObjects(L.tableMin.x(), L.tableMax.x(), L.tableMin.y(), L.tableMax.y(), tz, 7 + rng.index(4), true);

  // Shelf against y = 5: sides, back, boards, and books / boxes on each board.
  const S sx0 = S(0.8), sx1 = S(2.6), sy0 = Y - S(0.38), sy1 = Y - S(0.02);
  b.box(V3(sx0, sy0, 0), V3(sx0 + S(0.03), sy1, S(2.0)), mWood, mWood, -1);
  b.box(V3(sx1 - S(0.03), sy0, 0), V3(sx1, sy1, S(2.0)), mWood, mWood, -1);
  b.quad(V3(sx1, sy1, 0), V3(sx1, sy1, S(2.0)), V3(sx0, sy1, S(2.0)), V3(sx0, sy1, 0), mWoodDark);
  for (int k = 0; k < 5; ++k) {
    const S z = S(0.05) + S(0.4) * S(k);
    b.box(V3(sx0 + S(0.03), sy0, z - S(0.025)), V3(sx1 - S(0.03), sy1 - S(0.005), z), mWood, mWood, mWood);
    // A row of books, some gaps, the odd box.
    S x = sx0 + S(0.05) + S(rng.uniform(0, 0.1));
    while (x < sx1 - S(0.12)) {
      if (rng.chance(0.12)) {  // gap
        x += S(rng.uniform(0.05, 0.2));
        continue;
      }
      if (rng.chance(0.15)) {  // a box
        const S w = S(rng.uniform(0.12, 0.25));
        if (x + w > sx1 - S(0.04)) break;
        const int print = b.material(tClutterB, jitter(Rgb(1, 1, 1), 0.15f), 700 * tpm);
        const S hgt = S(rng.uniform(0.1, 0.3));
        const float bu = static_cast<float>(rng.uniform(0, 3));
        const float bv = static_cast<float>(rng.uniform(0, 3));
        b.box(V3(x, sy0 + S(0.04), z), V3(x + w, sy1 - S(0.04), z + hgt), print, print, -1, S(1), S(0), bu, bv);
        x += w + S(0.01);
        continue;
      }
      const S w = S(rng.uniform(0.02, 0.055)), hgt = S(rng.uniform(0.18, 0.34)), d = S(rng.uniform(0.15, 0.3));
      if (x + w > sx1 - S(0.04)) break;
      const Rgb base = paletteColour(h()) * (1.0f / 215.0f);
      const Rgb tint = jitter(base, 0.15f);
      const int spine = b.material(tStripes, tint, 1200 * tpm);
      const float bu = static_cast<float>(rng.uniform(0, 1));
      const float bv = static_cast<float>(rng.uniform(0, 1));
      b.box(V3(x, sy1 - S(0.03) - d, z), V3(x + w, sy1 - S(0.03), z + hgt), spine, spine, -1, S(1), S(0), bu, bv);
      x += w + S(0.002);
    }
  }
  // Sideboard against x = 6 with objects on top.
  const S bz = S(0.9);
  b.box(V3(X - S(0.45), S(1.2), 0), V3(X - S(0.01), S(3.6), bz), mWood, mWoodDark, -1);
  for (int k = 0; k < 3; ++k) {  // drawer fronts with handles
    const S y0 = S(1.25) + S(0.8) * S(k);
    b.box(V3(X - S(0.46), y0, S(0.1)), V3(X - S(0.45), y0 + S(0.7), S(0.8)), mWoodDark, -1, -1);
    b.box(V3(X - S(0.49), y0 + S(0.3), S(0.62)), V3(X - S(0.46), y0 + S(0.4), S(0.65)), mFrame, mFrame, mFrame);
  }
  placeObjects(X - S(0.44), X - S(0.02), S(1.21), S(3.59), bz, 5 + rng.index(3), true);

  b.finish();
  // Walking loop and standing spots (see RoomLayout).
  scene.layout = L;
  scene.layout.walkLoop = {Vec2<Scalar>(S(1.2), S(0.9)), Vec2<Scalar>(S(4.8), S(0.9)), Vec2<Scalar>(S(4.85), S(3.8)),
                           Vec2<Scalar>(S(1.25), S(3.85))};
  scene.layout.standSpots = {Vec2<Scalar>(S(1.25), S(1.1)), Vec2<Scalar>(S(4.6), S(1.0)), Vec2<Scalar>(S(4.7), S(3.8)),
                             Vec2<Scalar>(S(1.3), S(3.9)), Vec2<Scalar>(S(3.0), S(3.7))};
  return scene;
}

}  // namespace synth
}  // namespace hawor
