// hawor/synth/renderer.hpp — renders one frame of the synthetic scene with hands: textured,
// Lambert-shaded RGB, metric depth and a labelled hand mask, with the software rasteriser of
// render/rasterizer.hpp.
//
// Two passes. (1) Visibility: the scene and every hand mesh go through one Rasterizer with one
// z-buffer (no culling, near plane 1 cm); the fragment functor keeps, per pixel, the id of the
// nearest face (scene faces first, then each hand's faces) and its q = b/z (perspective-correct
// barycentrics up to the depth). The z-buffer IS the depth image: metres along the optical axis
// (docs/design.md §2), +inf where nothing was drawn (never inside the closed room). (2) Shading, once per
// pixel:
//   scene   texture(material, uv = Σ b_i·uv_i) × tint × shade(face), trilinear texture filtering
//           with a footprint of z·texelsPerMetre / (fx·max(|cos θ|, 0.2)) level-0 texels (θ: angle
//           between the face normal and the pixel ray); shade = ambient + Σ I_k·max(0, n·l_k)
//           with the room's fixed lights and the face normal turned towards the camera
//   hands   albedo × the same Lambert model with the interpolated vertex normal (area-weighted
//           face normals of the posed mesh, turned towards the camera), lights in camera frame
//   noise   optional zero-mean sensor noise: per channel a triangular variate from two bytes of
//           a hash of (seed, pixel), standard deviation `noiseSigma` grey levels (deterministic,
//           no libm)
// The mask gets each hand's label where that hand is the nearest surface, 0 elsewhere: exactly
// "the hand mesh is nearer than the scene" (and the nearer hand where the two overlap).
// renderLinear() stops before the noise and the rounding to bytes (float colour for the capture
// model of capture.hpp); setCamera() renders through another camera, e.g. a band of rows.
// Thread-safety: a SceneRenderer holds scratch buffers; use one per thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/render/image.hpp"
#include "hawor/render/rasterizer.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/scene.hpp"
#include "hawor/synth/texture.hpp"
#include "hawor/synth/trajectory.hpp"

namespace hawor {
namespace synth {

/// A hand mesh to draw: camera-frame vertices (V,3), faces, colour and mask label (1..255).
template <typename Scalar>
struct HandMeshView {
  const Points3<Scalar>* vertices = nullptr;
  const TriangleList* faces = nullptr;
  Rgb albedo{215.0f, 160.0f, 130.0f};
  std::uint8_t label = 255;
};

/// The images of one rendered frame.
struct RenderedImages {
  ImageU8 rgb;    ///< W × H × 3, sRGB bytes
  ImageF depth;   ///< W × H, metres along z; +inf where nothing was drawn
  ImageU8 mask;   ///< W × H, hand labels (0 = not a hand)
  std::vector<int> handPixels;  ///< visible pixels per hand mesh (in the order given)
};

template <typename Scalar>
class SceneRenderer {
 public:
  SceneRenderer(const IndoorScene<Scalar>& scene, const PinholeCamera<Scalar>& camera)
      : scene_(&scene), cam_(camera), raster_(camera, rasterOptions()) {
    if (static_cast<int>(scene.uv.size()) != 2 * scene.numVertices() ||
        static_cast<int>(scene.faceMaterial.size()) != scene.numFaces()) {
      throw Error("SceneRenderer: the scene's uv / faceMaterial sizes do not match its mesh");
    }
    for (int m : scene.faceMaterial) {
      if (m < 0 || m >= static_cast<int>(scene.materials.size())) throw Error("SceneRenderer: face material out of range");
    }
    for (const SceneMaterial& m : scene.materials) {
      if (m.texture < 0 || m.texture >= static_cast<int>(scene.textures.size())) {
        throw Error("SceneRenderer: material texture out of range");
      }
    }
    sceneNormals_.resize(static_cast<std::size_t>(scene.numFaces()));
    for (int f = 0; f < scene.numFaces(); ++f) sceneNormals_[static_cast<std::size_t>(f)] = scene.faceNormal(f);
  }

  const PinholeCamera<Scalar>& camera() const { return cam_; }

  /// Renders the scene seen by a camera with pose `roomFromCamera` (camera → room frame) and the
  /// hand meshes (already in the camera frame). noiseSigma ≥ 0 (grey levels), noiseSeed picks
  /// the noise pattern (e.g. a hash of the sequence seed and the frame index).
  void render(const RigidPose<Scalar>& roomFromCamera, const std::vector<HandMeshView<Scalar>>& hands, float noiseSigma,
              std::uint32_t noiseSeed, RenderedImages& out) {
    draw(roomFromCamera, hands, out);
    const int W = cam_.width;
    out.rgb.resize(W, cam_.height, 3);
    const float noiseScale = noiseSigma * 2.449489743f / 255.0f;  // triangular on [−a, a]: σ = a/√6
    shade(hands, out, [&](int x, int y, Rgb c) {
      if (noiseSigma > 0.0f) {
        const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
        const std::uint32_t r1 = hash32(noiseSeed ^ (static_cast<std::uint32_t>(p) * 0x9E3779B1u));
        const std::uint32_t r2 = hash32(r1 ^ 0x68E31DA4u);
        const float s = noiseScale;
        c.r += s * (static_cast<float>(r1 & 0xFFu) + static_cast<float>((r1 >> 8) & 0xFFu) - 255.0f);
        c.g += s * (static_cast<float>((r1 >> 16) & 0xFFu) + static_cast<float>(r1 >> 24) - 255.0f);
        c.b += s * (static_cast<float>(r2 & 0xFFu) + static_cast<float>((r2 >> 8) & 0xFFu) - 255.0f);
      }
      std::uint8_t* px = out.rgb.row(y) + 3 * x;
      px[0] = toByte(c.r);
      px[1] = toByte(c.g);
      px[2] = toByte(c.b);
    });
  }

  /// The same render without noise and before quantisation: `rgb` (W × H × 3 float, grey levels,
  /// not clamped) for the capture model of capture.hpp; out.depth, out.mask and out.handPixels as
  /// render() fills them; out.rgb is left alone.
  void renderLinear(const RigidPose<Scalar>& roomFromCamera, const std::vector<HandMeshView<Scalar>>& hands, ImageF& rgb,
                    RenderedImages& out) {
    draw(roomFromCamera, hands, out);
    rgb.resize(cam_.width, cam_.height, 3);
    shade(hands, out, [&](int x, int y, const Rgb& c) {
      float* px = rgb.row(y) + 3 * x;
      px[0] = c.r;
      px[1] = c.g;
      px[2] = c.b;
    });
  }

  /// Renders through another pinhole camera from now on (e.g. a band of rows of a larger image:
  /// the same fx, fy, cx, with cy − y0 and height h renders rows [y0, y0 + h) of it).
  void setCamera(const PinholeCamera<Scalar>& camera) {
    cam_ = camera;
    raster_ = Rasterizer<Scalar>(camera, rasterOptions());
  }

  /// Area-weighted vertex normals of a mesh (unit length; zero for unused vertices).
  static void vertexNormals(const Points3<Scalar>& V, const TriangleList& F, Points3<Scalar>& N) {
    N.setZero(V.rows(), 3);
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      const Vec3<Scalar> a = V.row(F(f, 0)).transpose(), b = V.row(F(f, 1)).transpose(), c = V.row(F(f, 2)).transpose();
      const Vec3<Scalar> n = (b - a).cross(c - a);
      for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
    }
    for (Eigen::Index i = 0; i < N.rows(); ++i) {
      const Scalar len = N.row(i).norm();
      if (len > Scalar(0)) N.row(i) /= len;
    }
  }


 private:
  // Pass 1 (file comment): scene in the camera frame, per-face records, visibility into ids_ /
  // qs_ and out.depth; hand vertex normals and the lights in the camera frame for pass 2.
  void draw(const RigidPose<Scalar>& roomFromCamera, const std::vector<HandMeshView<Scalar>>& hands, RenderedImages& out) {
    const IndoorScene<Scalar>& S = *scene_;
    const int W = cam_.width, H = cam_.height;
    const std::size_t N = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    for (const HandMeshView<Scalar>& h : hands) {
      if (!h.vertices || !h.faces) throw Error("SceneRenderer: a hand mesh has no vertices or faces");
    }
    // Scene in the camera frame.
    const RigidPose<Scalar> camFromRoom = roomFromCamera.inverse();
    camVerts_.resize(S.vertices.rows(), 3);
    for (Eigen::Index i = 0; i < S.vertices.rows(); ++i) {
      camVerts_.row(i) = (camFromRoom.R * S.vertices.row(i).transpose() + camFromRoom.t).transpose();
    }
    // Everything pass 2 needs of a scene face, gathered once per frame into one record (one
    // cache line per face): texture, scale, tint × Lambert shade (normal turned towards the
    // camera), camera-frame normal, the three texture coordinates.
    const int F = S.numFaces();
    faces_.resize(static_cast<std::size_t>(F));
    for (int f = 0; f < F; ++f) {
      Vec3<Scalar> n = sceneNormals_[static_cast<std::size_t>(f)];
      const Vec3<Scalar> p0 = S.vertices.row(S.faces(f, 0)).transpose();
      if (n.dot(p0 - roomFromCamera.t) > Scalar(0)) n = -n;
      const SceneMaterial& m = S.materials[static_cast<std::size_t>(S.faceMaterial[static_cast<std::size_t>(f)])];
      FaceRecord& r = faces_[static_cast<std::size_t>(f)];
      r.texture = &S.textures[static_cast<std::size_t>(m.texture)];
      r.texelsPerMetre = m.texelsPerMetre;
      r.colour = m.tint * S.shade(n);
      const Vec3<Scalar> nc = camFromRoom.R * n;
      r.n[0] = static_cast<float>(nc.x());
      r.n[1] = static_cast<float>(nc.y());
      r.n[2] = static_cast<float>(nc.z());
      for (int k = 0; k < 3; ++k) {
        const std::size_t v = static_cast<std::size_t>(S.faces(f, k));
        r.u[k] = S.uv[2 * v] * m.texelsPerMetre;
        r.v[k] = S.uv[2 * v + 1] * m.texelsPerMetre;
      }
    }
    // Pass 1: visibility.
    raster_.clearDepth(out.depth);
    raster_.setDepthBuffer(&out.depth);
    ids_.assign(N, -1);
    qs_.resize(3 * N);
    int* ids = ids_.data();
    float* qs = qs_.data();
    auto visit = [ids, qs, W](int offset) {
      return [ids, qs, W, offset](const Fragment<Scalar>& fr) {
        const std::size_t p = static_cast<std::size_t>(fr.y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(fr.x);
        ids[p] = offset + fr.face;
        qs[3 * p] = static_cast<float>(fr.q0);
        qs[3 * p + 1] = static_cast<float>(fr.q1);
        qs[3 * p + 2] = static_cast<float>(fr.q2);
      };
    };
    raster_.drawMesh(camVerts_, S.faces, visit(0));
    handOffset_.assign(hands.size() + 1, F);
    for (std::size_t h = 0; h < hands.size(); ++h) {
      raster_.drawMesh(*hands[h].vertices, *hands[h].faces, visit(handOffset_[h]));
      handOffset_[h + 1] = handOffset_[h] + static_cast<int>(hands[h].faces->rows());
    }
    raster_.setDepthBuffer(nullptr);
    // Hand vertex normals (camera frame, float) and the lights in the camera frame.
    handNormals_.resize(hands.size());
    for (std::size_t h = 0; h < hands.size(); ++h) {
      vertexNormals(*hands[h].vertices, *hands[h].faces, normalScratch_);
      handNormals_[h] = normalScratch_.template cast<float>();
    }
    const Vec3<Scalar> l1s = camFromRoom.R * S.lightDir1, l2s = camFromRoom.R * S.lightDir2;
    for (int k = 0; k < 3; ++k) {
      light1_[k] = static_cast<float>(l1s(k));
      light2_[k] = static_cast<float>(l2s(k));
    }
  }

  // Pass 2 (file comment): the colour of every pixel, handed to sink(x, y, Rgb) row by row;
  // fills out.mask and out.handPixels.
  template <typename Sink>
  void shade(const std::vector<HandMeshView<Scalar>>& hands, RenderedImages& out, Sink sink) {
    const IndoorScene<Scalar>& S = *scene_;
    const int W = cam_.width, H = cam_.height, F = S.numFaces();
    const int* ids = ids_.data();
    const float* qs = qs_.data();
    const float* l1 = light1_;
    const float* l2 = light2_;
    out.mask.resize(W, H, 1, 0);
    out.handPixels.assign(hands.size(), 0);
    const float fx = static_cast<float>(cam_.fx), fy = static_cast<float>(cam_.fy);
    const float cx = static_cast<float>(cam_.cx), cy = static_cast<float>(cam_.cy);
    for (int y = 0; y < H; ++y) {
      std::uint8_t* maskRow = out.mask.row(y);
      const float* depthRow = out.depth.row(y);
      const float ry = (static_cast<float>(y) - cy) / fy;
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
        const int id = ids[p];
        Rgb c(0, 0, 0);
        if (id >= 0) {
          const float z = depthRow[x];
          const float b0 = qs[3 * p] * z, b1 = qs[3 * p + 1] * z, b2 = qs[3 * p + 2] * z;
          const float rx = (static_cast<float>(x) - cx) / fx;
          const float invLen = 1.0f / std::sqrt(rx * rx + ry * ry + 1.0f);
          if (id < F) {
            const FaceRecord& r = faces_[static_cast<std::size_t>(id)];
            const float u = b0 * r.u[0] + b1 * r.u[1] + b2 * r.u[2];
            const float v = b0 * r.v[0] + b1 * r.v[1] + b2 * r.v[2];
            float cosT = std::abs(r.n[0] * rx + r.n[1] * ry + r.n[2]) * invLen;
            if (cosT < 0.2f) cosT = 0.2f;
            const float footprint = z * r.texelsPerMetre / (fx * cosT);
            c = r.texture->sample(u, v, footprint).mul(r.colour);
          } else {
            std::size_t h = 0;
            while (id >= handOffset_[h + 1]) ++h;
            const int f = id - handOffset_[h];
            const TriangleList& fc = *hands[h].faces;
            const float* n0 = handNormals_[h].data() + 3 * fc(f, 0);
            const float* n1 = handNormals_[h].data() + 3 * fc(f, 1);
            const float* n2 = handNormals_[h].data() + 3 * fc(f, 2);
            float n[3];
            for (int k = 0; k < 3; ++k) n[k] = b0 * n0[k] + b1 * n1[k] + b2 * n2[k];
            float nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (n[0] * rx + n[1] * ry + n[2] > 0.0f) nn = -nn;  // turned towards the camera
            const float inv = nn != 0.0f ? 1.0f / nn : 0.0f;
            const float d1 = (n[0] * l1[0] + n[1] * l1[1] + n[2] * l1[2]) * inv;
            const float d2 = (n[0] * l2[0] + n[1] * l2[1] + n[2] * l2[2]) * inv;
            const float shade = S.ambient + S.light1 * (d1 > 0.0f ? d1 : 0.0f) + S.light2 * (d2 > 0.0f ? d2 : 0.0f);
            c = hands[h].albedo * shade;
            maskRow[x] = hands[h].label;
            ++out.handPixels[h];
          }
        }
        sink(x, y, c);
      }
    }
  }

  static std::uint8_t toByte(float v) {
    const float c = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
    return static_cast<std::uint8_t>(c + 0.5f);
  }

  const IndoorScene<Scalar>* scene_;
  PinholeCamera<Scalar> cam_;
  Rasterizer<Scalar> raster_;
  std::vector<Vec3<Scalar>> sceneNormals_;
  Points3<Scalar> camVerts_;
  /// Per scene face, for the shading pass (see render()).
  struct FaceRecord {
    const Texture* texture = nullptr;
    float texelsPerMetre = 0;
    Rgb colour;
    float n[3] = {0, 0, 0};
    float u[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  };
  std::vector<FaceRecord> faces_;
  Points3<Scalar> normalScratch_;
  std::vector<int> ids_;
  std::vector<float> qs_;
  std::vector<int> handOffset_;
  std::vector<Points3<float>> handNormals_;
  float light1_[3] = {0, 0, 0}, light2_[3] = {0, 0, 0};  ///< the lights in the camera frame

  static RasterOptions<Scalar> rasterOptions() {
    RasterOptions<Scalar> ro;
    ro.nearPlane = Scalar(0.01);
    ro.cull = CullMode::None;
    return ro;
  }
};

}  // namespace synth
}  // namespace hawor
