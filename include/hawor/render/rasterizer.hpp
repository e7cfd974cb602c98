// hawor/render/rasterizer.hpp — software rasterisation of camera-frame triangles through a
// pinhole camera: near-plane clipping, z-buffer, top-left fill rule, perspective-correct
// barycentrics handed to a per-pixel functor.
//
// Conventions (docs/design.md §2): OpenCV camera frame (x right, y down, z forward); pixel centres at
// integer coordinates, a pixel (x, y) is drawn iff its centre (x, y) lies inside the projected
// triangle. Depth is metres along z (not the ray length).
//
// Pipeline per triangle P0, P1, P2 (camera frame):
//  1. Outcodes against 5 planes: the near plane z = near and a guard band |u|, |v| ≤ 2^20 px.
//     All three outside one plane → rejected. All inside → fast path. Otherwise the triangle is
//     clipped (Sutherland–Hodgman in homogeneous screen coordinates h = K·P, double) and the
//     polygon drawn as a fan. Crossing z = near is clipped, never dropped; the guard band keeps
//     the fixed-point maths below from overflowing for huge or near-plane coordinates without
//     changing any pixel of the image. Each clip point is snapped exactly onto its plane, so
//     interpolating between huge coordinates (tested up to 1e30 m) cannot drift off the band.
//  2. Vertices are projected and snapped to 1/256 px (fixed point, 64-bit edge functions), so
//     coverage is exact: with the top-left rule (D3D/OpenGL convention for y-down images: a
//     sample on an edge belongs to the triangle iff the edge is a top or a left edge) adjacent
//     triangles that share an edge never both cover, nor both miss, a pixel centre on it.
//     Clip points are computed from the (inside, outside) vertex pair, whichever way round the
//     edge runs, so neighbours clip a shared edge to bit-identical points.
//  3. Perspective-correct barycentrics from the homogeneous form (Olano & Greer 1997): with
//     M = [P0 P1 P2] (columns) and the pixel ray d = ((x − cx)/fx, (y − cy)/fy, 1), the ray
//     meets the triangle's plane at P = z·d with barycentrics b = z·M⁻¹d, so q = b/z = M⁻¹d is
//     affine in (x, y); z = 1/Σq and b = q·z. Barycentrics always refer to the ORIGINAL triangle,
//     also for pixels of clipped parts. det M = P0·(P1×P2) < 0 ⇔ the triangle's normal
//     (P1−P0)×(P2−P0) points at the camera ⇔ front face (counter-clockwise seen from outside,
//     the usual outward winding of MANO's right hand).
//  4. Bounding box (clamped to the image); per row the exact covered span follows from the
//     integer edge functions with an incremental DDA, so only covered pixels are visited.
// Degenerate input: triangles with a non-finite vertex, zero area (det M = 0, or zero area
// after snapping), entirely behind the near plane, or so large that the setup overflows double
// (coordinates beyond ~1e100 m) are skipped; faces indexing outside the vertex array throw
// hawor::Error before anything is drawn.
// Thread-safety: a Rasterizer holds scratch buffers; use one per thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// Row-major (F,3) vertex indices of triangles (the same type as hawor::Faces of the hand module).
using TriangleList = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Which faces to skip. Front face: det[P0 P1 P2] < 0 (normal towards the camera, see above).
enum class CullMode { None, Back, Front };

template <typename Scalar>
struct RasterOptions {
  Scalar nearPlane = Scalar(1e-3);  ///< metres; geometry with z < nearPlane is clipped away
  CullMode cull = CullMode::None;
};

/// One covered pixel. q_i = b_i / z (affine in screen space); barycentrics and depth on demand,
/// so a functor that reads neither pays for neither.
template <typename Scalar>
struct Fragment {
  int x = 0, y = 0;  ///< pixel
  int face = -1;     ///< face index (drawMesh) or the id given to drawTriangle
  Scalar q0 = Scalar(0), q1 = Scalar(0), q2 = Scalar(0);

  /// 1/z at the pixel centre.
  Scalar inverseDepth() const { return q0 + q1 + q2; }
  /// z (metres along the optical axis) of the triangle's plane at the pixel centre's ray.
  Scalar depth() const { return Scalar(1) / (q0 + q1 + q2); }
  /// Perspective-correct barycentrics (b0, b1, b2) w.r.t. the original triangle, Σb = 1.
  /// Within rounding of the 1/256 px snapping they lie in [0, 1].
  Vec3<Scalar> barycentric() const {
    const Scalar z = depth();
    return Vec3<Scalar>(q0 * z, q1 * z, q2 * z);
  }
};

namespace render_detail {

constexpr int kSubBits = 8;                    ///< sub-pixel precision: 1/256 px
constexpr std::int64_t kSub = 1 << kSubBits;  ///< fixed-point units per pixel
/// Guard band in pixels. Fixed coordinates stay below 2^28, edge functions below 2^59.
constexpr double kGuard = 1048576.0;
constexpr int kMaxImageSide = 65536;

enum : unsigned {
  kOutNear = 1u,
  kOutLeft = 2u,
  kOutRight = 4u,
  kOutTop = 8u,
  kOutBottom = 16u,
  kInvalid = 32u
};

/// Homogeneous screen coordinates h = K·P = (fx·x + cx·z, fy·y + cy·z, z): u = h0/h2, v = h1/h2.
struct H3 {
  double h[3];
};

/// A vertex after projection: homogeneous screen position, outcode and (when code == 0) its
/// snapped screen position in 1/256 px.
struct ProjVertex {
  H3 p;
  std::int64_t X = 0, Y = 0;
  unsigned code = 0;
};

/// ⌊a/b⌋ for b > 0 and |a| < 2^62. A double quotient (relative error 2^−53, so off by at most
/// one here) corrected exactly; faster than a 64-bit idiv, which dominated the triangle setup.
inline std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  std::int64_t q = static_cast<std::int64_t>(static_cast<double>(a) / static_cast<double>(b));
  while (q * b > a) --q;
  while ((q + 1) * b <= a) ++q;
  return q;
}
inline std::int64_t ceilDiv(std::int64_t a, std::int64_t b) { return -floorDiv(-a, b); }

/// Round half away from zero (std::llround without the libm call).
inline std::int64_t roundToInt(double v) {
  return static_cast<std::int64_t>(v + (v >= 0.0 ? 0.5 : -0.5));
}

/// Camera constants and the 5 clip planes, in double, in homogeneous screen coordinates.
struct ClipCamera {
  double fx, fy, cx, cy, nearPlane;

  H3 toScreen(double x, double y, double z) const {
    return {{fx * x + cx * z, fy * y + cy * z, z}};
  }

  /// Plane i (≥ 0 inside): 0 z ≥ near, 1 u ≥ −G, 2 u ≤ G, 3 v ≥ −G, 4 v ≤ G, written so that
  /// they are linear in h (u ≥ −G ⇔ h0 + G·h2 ≥ 0 for h2 > 0).
  double plane(int i, const H3& p) const {
    switch (i) {
      case 0: return p.h[2] - nearPlane;
      case 1: return p.h[0] + kGuard * p.h[2];
      case 2: return kGuard * p.h[2] - p.h[0];
      case 3: return p.h[1] + kGuard * p.h[2];
      default: return kGuard * p.h[2] - p.h[1];
    }
  }

  /// Puts a freshly clipped point exactly on plane i. Interpolating between huge coordinates
  /// loses the small ones to cancellation; snapping keeps every clipped vertex on its plane, so
  /// after the u planes all |u| ≤ G and later interpolations of u stay accurate (same for v).
  void snap(int i, H3& p) const {
    switch (i) {
      case 0: p.h[2] = nearPlane; break;
      case 1: p.h[0] = -kGuard * p.h[2]; break;
      case 2: p.h[0] = kGuard * p.h[2]; break;
      case 3: p.h[1] = -kGuard * p.h[2]; break;
      default: p.h[1] = kGuard * p.h[2]; break;
    }
  }

  unsigned outcode(const H3& p) const {
    if (!std::isfinite(p.h[0]) || !std::isfinite(p.h[1]) || !std::isfinite(p.h[2])) {
      return kInvalid;
    }
    unsigned c = 0;
    for (int i = 0; i < 5; ++i) {
      if (plane(i, p) < 0.0) c |= 1u << i;
    }
    return c;
  }

  /// Snapped projection of a point with h2 > 0. The single place where screen positions are
  /// made, so that shared vertices snap identically in every triangle. Clamped to the guard
  /// band (a no-op for points inside it) so that no input can overflow the edge functions.
  static void project(const H3& p, std::int64_t& X, std::int64_t& Y) {
    const double lim = (kGuard + 1.0) * double(kSub);
    const double u = std::min(lim, std::max(-lim, p.h[0] / p.h[2] * double(kSub)));
    const double v = std::min(lim, std::max(-lim, p.h[1] / p.h[2] * double(kSub)));
    X = roundToInt(u);
    Y = roundToInt(v);
  }

  ProjVertex make(double x, double y, double z) const {
    ProjVertex v;
    v.p = toScreen(x, y, z);
    v.code = outcode(v.p);
    if (v.code == 0) project(v.p, v.X, v.Y);
    return v;
  }
};

/// What fillTriangle reports: fragments, fragments that pass the z-test, or covered row spans.
enum class FillMode { Pixels, PixelsDepth, Spans };

/// Exact integer DDA of one edge's column bound along successive rows (see fillTriangle).
/// Lower bound: q = ⌈N/s⌉ with N = −e, N = q·s − rem; upper bound: q = ⌊e/s⌋, e = q·s + rem;
/// 0 ≤ rem < s in both. Per row N (resp. e) changes by a constant split as dq·s + dr with
/// 0 ≤ dr < s, so one conditional carry keeps the invariant (written branch-free: the carry
/// depends on the data and would be mispredicted).
struct EdgeStep {
  std::int64_t q = 0, rem = 0, s = 1, dq = 0, dr = 0;

  void initLower(std::int64_t e, std::int64_t step, std::int64_t stepY) {
    s = step;
    q = -floorDiv(e, s);  // ⌈−e/s⌉
    rem = q * s + e;      // q·s − (−e)
    dq = floorDiv(-stepY, s);
    dr = -stepY - dq * s;
  }
  void nextLower() {
    rem -= dr;
    const std::int64_t carry = -static_cast<std::int64_t>(rem < 0);  // 0 or −1 (all ones)
    rem += s & carry;
    q += dq - carry;
  }
  void initUpper(std::int64_t e, std::int64_t step, std::int64_t stepY) {
    s = step;
    q = floorDiv(e, s);
    rem = e - q * s;
    dq = floorDiv(stepY, s);
    dr = stepY - dq * s;
  }
  void nextUpper() {
    rem += dr;
    const std::int64_t carry = -static_cast<std::int64_t>(rem >= s);
    rem -= s & carry;
    q += dq - carry;
  }
  /// A bound that never binds (q fixed), used to pad to two lower and two upper edges.
  void initConstant(std::int64_t value) {
    q = value;
    rem = 0;
    s = 1;
    dq = 0;
    dr = 0;
  }
};

/// q_i(x, y) = a_i·x + b_i·y + c_i for one triangle (see the file comment, step 3).
template <typename Scalar>
struct PlaneSetup {
  Scalar a[3], b[3], c[3];
  Scalar aSum, bSum, cSum;  ///< 1/z = Σq_i as one affine function (the depth test's)
  int face;
};

}  // namespace render_detail

/// Rasterises camera-frame triangles into a width × height pixel grid (the camera's size),
/// calling fn(const Fragment<Scalar>&) once per covered pixel centre that passes the optional
/// depth test. The functor is a template parameter (inlined; no std::function in the loop),
/// taken by value and copied freely like the functors of <algorithm>: keep state behind
/// references or pointers.
///
/// Depth test (setDepthBuffer): a fragment passes iff its depth is below the stored value
/// (tested as (1/z)·stored > 1 in float, so hidden fragments cost no division), and then stores
/// its depth as a float; initialise the buffer with +inf (clearDepth). Without a depth buffer
/// every covered pixel of every triangle is reported, in face order.
template <typename Scalar>
class Rasterizer {
 public:
  explicit Rasterizer(const PinholeCamera<Scalar>& camera,
                      const RasterOptions<Scalar>& options = RasterOptions<Scalar>())
      : cam_(camera), opt_(options) {
    cam_.validate();
    if (cam_.width > render_detail::kMaxImageSide || cam_.height > render_detail::kMaxImageSide) {
      throw Error("Rasterizer: image size " + std::to_string(cam_.width) + "x" +
                  std::to_string(cam_.height) + " exceeds 65536");
    }
    if (!(opt_.nearPlane > Scalar(0)) || !std::isfinite(static_cast<double>(opt_.nearPlane))) {
      throw Error("Rasterizer: nearPlane must be finite and > 0");
    }
    clip_ = {double(cam_.fx), double(cam_.fy), double(cam_.cx), double(cam_.cy),
             double(opt_.nearPlane)};
  }

  const PinholeCamera<Scalar>& camera() const { return cam_; }
  const RasterOptions<Scalar>& options() const { return opt_; }

  /// Depth buffer for the z-test (width × height × 1, metres along z), or nullptr for none.
  /// The buffer is borrowed: it must outlive the draw calls.
  void setDepthBuffer(Image<float>* depth) {
    if (depth && !depth->sameSize(cam_.width, cam_.height, 1)) {
      throw Error("Rasterizer: depth buffer is " + std::to_string(depth->width) + "x" +
                  std::to_string(depth->height) + "x" + std::to_string(depth->channels) +
                  ", expected " + std::to_string(cam_.width) + "x" + std::to_string(cam_.height) +
                  "x1");
    }
    depth_ = depth;
  }
  Image<float>* depthBuffer() const { return depth_; }

  /// Resizes `depth` to the camera's size and fills it with +inf.
  void clearDepth(Image<float>& depth) const {
    depth.resize(cam_.width, cam_.height, 1, std::numeric_limits<float>::infinity());
  }

  /// Draws every face of a mesh. vertices: (V,3) camera frame (metres); faces: (F,3) indices.
  /// Each vertex is projected once. Fragment::face is the face's row.
  template <typename Fn>
  void drawMesh(const Eigen::Ref<const Points3<Scalar>>& vertices,
                const Eigen::Ref<const TriangleList>& faces, Fn fn) {
    checkDepth();
    if (depth_) {
      drawAll<render_detail::FillMode::PixelsDepth>(vertices, faces, fn);
    } else {
      drawAll<render_detail::FillMode::Pixels>(vertices, faces, fn);
    }
  }

  /// Coverage only, the fast path for masks: fn(int y, int xBegin, int xEnd) once per row and
  /// triangle for its covered pixels [xBegin, xEnd) of row y (same coverage as drawMesh, no
  /// depth test, no barycentrics).
  template <typename Fn>
  void drawMeshSpans(const Eigen::Ref<const Points3<Scalar>>& vertices,
                     const Eigen::Ref<const TriangleList>& faces, Fn fn) {
    drawAll<render_detail::FillMode::Spans>(vertices, faces, fn);
  }

  /// Draws one camera-frame triangle; Fragment::face = id.
  template <typename Fn>
  void drawTriangle(const Vec3<Scalar>& p0, const Vec3<Scalar>& p1, const Vec3<Scalar>& p2,
                    Fn fn, int id = 0) {
    checkDepth();
    const render_detail::ProjVertex v0 = clip_.make(double(p0(0)), double(p0(1)), double(p0(2)));
    const render_detail::ProjVertex v1 = clip_.make(double(p1(0)), double(p1(1)), double(p1(2)));
    const render_detail::ProjVertex v2 = clip_.make(double(p2(0)), double(p2(1)), double(p2(2)));
    if (depth_) {
      drawFace<render_detail::FillMode::PixelsDepth>(v0, v1, v2, id, fn);
    } else {
      drawFace<render_detail::FillMode::Pixels>(v0, v1, v2, id, fn);
    }
  }

 private:
  using PV = render_detail::ProjVertex;
  using H3 = render_detail::H3;
  using FillMode = render_detail::FillMode;

  /// The borrowed depth buffer may have been resized since setDepthBuffer.
  void checkDepth() const {
    if (depth_ && !depth_->sameSize(cam_.width, cam_.height, 1)) {
      throw Error("Rasterizer: the depth buffer no longer matches the camera's image size");
    }
  }

  template <FillMode kMode, typename Fn>
  void drawAll(const Eigen::Ref<const Points3<Scalar>>& vertices,
               const Eigen::Ref<const TriangleList>& faces, Fn& fn) {
    const Eigen::Index nv = vertices.rows();
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int i = faces(f, k);
        if (i < 0 || i >= nv) {
          throw Error("Rasterizer::drawMesh: face " + std::to_string(f) + " references vertex " +
                      std::to_string(i) + " but there are " + std::to_string(nv) + " vertices");
        }
      }
    }
    verts_.resize(static_cast<std::size_t>(nv));
    for (Eigen::Index i = 0; i < nv; ++i) {
      verts_[i] =
          clip_.make(double(vertices(i, 0)), double(vertices(i, 1)), double(vertices(i, 2)));
    }
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      drawFace<kMode>(verts_[faces(f, 0)], verts_[faces(f, 1)], verts_[faces(f, 2)],
                      static_cast<int>(f), fn);
    }
  }

  template <FillMode kMode, typename Fn>
  void drawFace(const PV& v0, const PV& v1, const PV& v2, int face, Fn& fn) {
    using namespace render_detail;
    const unsigned any = v0.code | v1.code | v2.code;
    if ((any & kInvalid) || (v0.code & v1.code & v2.code)) return;

    // Plane of the original triangle in pixel coordinates (step 3): with H = [h0 h1 h2] = K·M,
    // q = M⁻¹d = H⁻¹(x, y, 1), i.e. q_i = (h_{i+1} × h_{i+2})·(x, y, 1) / det H, and
    // det H = fx·fy·det M has the sign of det M.
    const H3* P[3] = {&v0.p, &v1.p, &v2.p};
    double cr[3][3];
    for (int i = 0; i < 3; ++i) {
      const double* a = P[(i + 1) % 3]->h;
      const double* b = P[(i + 2) % 3]->h;
      cr[i][0] = a[1] * b[2] - a[2] * b[1];
      cr[i][1] = a[2] * b[0] - a[0] * b[2];
      cr[i][2] = a[0] * b[1] - a[1] * b[0];
    }
    const double det = v0.p.h[0] * cr[0][0] + v0.p.h[1] * cr[0][1] + v0.p.h[2] * cr[0][2];
    if (!(det != 0.0) || !std::isfinite(det)) return;
    if (opt_.cull == CullMode::Back && det > 0.0) return;
    if (opt_.cull == CullMode::Front && det < 0.0) return;
    PlaneSetup<Scalar> s{};
    s.face = face;
    for (int i = 0; i < 3 && kMode != FillMode::Spans; ++i) {
      const double ax = cr[i][0] / det, by = cr[i][1] / det, c = cr[i][2] / det;
      if (!std::isfinite(ax) || !std::isfinite(by) || !std::isfinite(c)) return;
      s.a[i] = static_cast<Scalar>(ax);
      s.b[i] = static_cast<Scalar>(by);
      s.c[i] = static_cast<Scalar>(c);
    }
    s.aSum = s.a[0] + s.a[1] + s.a[2];
    s.bSum = s.b[0] + s.b[1] + s.b[2];
    s.cSum = s.c[0] + s.c[1] + s.c[2];

    if (any == 0) {
      fillTriangle<kMode>(v0.X, v0.Y, v1.X, v1.Y, v2.X, v2.Y, s, fn);
      return;
    }
    // Sutherland–Hodgman against the planes some vertex is outside of (ping-pong buffers).
    H3 bufA[9], bufB[9];
    H3* in = bufA;
    H3* out = bufB;
    int n = 3;
    in[0] = v0.p;
    in[1] = v1.p;
    in[2] = v2.p;
    for (int plane = 0; plane < 5 && n >= 3; ++plane) {
      if (!(any & (1u << plane))) continue;
      int m = 0;
      for (int k = 0; k < n; ++k) {
        const H3& a = in[k];
        const H3& b = in[(k + 1) % n];
        const double da = clip_.plane(plane, a);
        const double db = clip_.plane(plane, b);
        if (da >= 0.0) out[m++] = a;
        if ((da >= 0.0) != (db >= 0.0)) {
          // Always from the inside point to the outside one: both triangles sharing this edge
          // get the same bits.
          const H3& pi = da >= 0.0 ? a : b;
          const H3& po = da >= 0.0 ? b : a;
          const double di = da >= 0.0 ? da : db;
          const double dout = da >= 0.0 ? db : da;
          const double t = di / (di - dout);
          H3& q = out[m++];
          for (int c = 0; c < 3; ++c) q.h[c] = pi.h[c] + t * (po.h[c] - pi.h[c]);
          clip_.snap(plane, q);
        }
      }
      std::swap(in, out);
      n = m;
    }
    if (n < 3) return;
    std::int64_t X[9], Y[9];
    for (int k = 0; k < n; ++k) {
      const H3& p = in[k];
      if (!std::isfinite(p.h[0]) || !std::isfinite(p.h[1]) || !(p.h[2] > 0.0)) return;
      render_detail::ClipCamera::project(p, X[k], Y[k]);
    }
    for (int k = 1; k + 1 < n; ++k) {
      fillTriangle<kMode>(X[0], Y[0], X[k], Y[k], X[k + 1], Y[k + 1], s, fn);
    }
  }

  /// Fills the pixel centres inside a snapped screen triangle (1/256 px units).
  template <FillMode kMode, typename Fn>
  void fillTriangle(std::int64_t x0, std::int64_t y0, std::int64_t x1, std::int64_t y1,
                    std::int64_t x2, std::int64_t y2, const render_detail::PlaneSetup<Scalar>& s,
                    Fn& fn) {
    using namespace render_detail;
    std::int64_t area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if (area == 0) return;
    if (area < 0) {  // make the orientation positive (y down): the edge tests below assume it
      std::swap(x1, x2);
      std::swap(y1, y2);
    }
    const std::int64_t px0 = std::max<std::int64_t>(0, ceilDiv(std::min({x0, x1, x2}), kSub));
    const std::int64_t px1 =
        std::min<std::int64_t>(cam_.width - 1, floorDiv(std::max({x0, x1, x2}), kSub));
    const std::int64_t py0 = std::max<std::int64_t>(0, ceilDiv(std::min({y0, y1, y2}), kSub));
    const std::int64_t py1 =
        std::min<std::int64_t>(cam_.height - 1, floorDiv(std::max({y0, y1, y2}), kSub));
    if (px0 > px1 || py0 > py1) return;

    // Edge k runs from a to b (opposite vertex k); E(p) = (b − a) × (p − a) ≥ 0 inside.
    // Top-left rule for this orientation: top edge ⇔ dy = 0 and dx > 0, left edge ⇔ dy < 0;
    // samples exactly on other edges are excluded (bias −1 on the integer edge function).
    // Along a row E is linear in the column offset j = x − px0: E = e + sx·j, sx = −dy·256, so
    // each edge bounds j from below (sx > 0: j ≥ ⌈−e/sx⌉), from above (sx < 0: j ≤ ⌊e/−sx⌋) or
    // not at all (horizontal: the whole row is in or out). From row to row e grows by
    // sy = dx·256; the bounds follow exactly with an integer DDA (quotient + remainder), so the
    // inner loop visits only covered pixels, with no per-pixel test and no division per row.
    // Horizontal edges (sx = 0) only cut whole rows: E = e + t·sy ≥ 0 for row offset t, so
    // they shrink [py0, py1] instead of costing work per row.
    const std::int64_t ax[3] = {x1, x2, x0}, ay[3] = {y1, y2, y0};
    const std::int64_t bx[3] = {x2, x0, x1}, by[3] = {y2, y0, y1};
    const std::int64_t sx0 = px0 * kSub;
    const std::int64_t jmax = px1 - px0;
    std::int64_t rowFirst = py0, rowLast = py1;
    std::int64_t edx[3], edy[3], bias[3];
    for (int k = 0; k < 3; ++k) {
      edx[k] = bx[k] - ax[k];
      edy[k] = by[k] - ay[k];
      const bool topLeft = edy[k] < 0 || (edy[k] == 0 && edx[k] > 0);
      bias[k] = topLeft ? 0 : 1;
      if (edy[k] == 0) {  // horizontal: E = e + t·sy over row offsets t from py0
        const std::int64_t e = edx[k] * (py0 * kSub - ay[k]) - bias[k];
        const std::int64_t stepY = edx[k] * kSub;
        if (stepY > 0) {
          rowFirst = std::max(rowFirst, py0 - floorDiv(e, stepY));  // t ≥ ⌈−e/sy⌉
        } else if (stepY < 0) {
          rowLast = std::min(rowLast, py0 + floorDiv(e, -stepY));  // t ≤ ⌊e/−sy⌋
        } else if (e < 0) {
          return;
        }
      }
    }
    if (rowFirst > rowLast) return;
    // Non-horizontal edges: DDA started at rowFirst.
    EdgeStep lower[2], upper[2];
    int nl = 0, nu = 0;
    const std::int64_t sy0 = rowFirst * kSub;
    for (int k = 0; k < 3; ++k) {
      if (edy[k] == 0) continue;
      const std::int64_t e = edx[k] * (sy0 - ay[k]) - edy[k] * (sx0 - ax[k]) - bias[k];
      const std::int64_t stepX = -edy[k] * kSub, stepY = edx[k] * kSub;
      if (stepX > 0 && nl < 2) {
        lower[nl++].initLower(e, stepX, stepY);
      } else if (stepX < 0 && nu < 2) {
        upper[nu++].initUpper(e, -stepX, stepY);
      }
    }
    if (nl == 0) lower[nl++].initConstant(0);
    if (nu == 0) upper[nu++].initConstant(jmax);
    // A triangle has one or two edges of each kind; specialised loops step only those.
    if (nl == 1 && nu == 1) {
      spanRows<kMode, 1, 1>(lower, upper, rowFirst, rowLast, px0, jmax, s, fn);
    } else if (nl == 1) {
      spanRows<kMode, 1, 2>(lower, upper, rowFirst, rowLast, px0, jmax, s, fn);
    } else if (nu == 1) {
      spanRows<kMode, 2, 1>(lower, upper, rowFirst, rowLast, px0, jmax, s, fn);
    } else {
      spanRows<kMode, 2, 2>(lower, upper, rowFirst, rowLast, px0, jmax, s, fn);
    }
  }

  /// The row loop of fillTriangle with NL lower and NU upper column bounds.
  template <FillMode kMode, int NL, int NU, typename Fn>
  void spanRows(render_detail::EdgeStep* lowerIn, render_detail::EdgeStep* upperIn,
                std::int64_t rowFirst, std::int64_t rowLast, std::int64_t px0, std::int64_t jmax,
                const render_detail::PlaneSetup<Scalar>& s, const Fn& fnIn) {
    // A local copy whose address never escapes: stores through the functor's pointers (bytes of
    // a mask may alias anything) then cannot clobber its captures, which stay in registers.
    Fn fn(fnIn);
    render_detail::EdgeStep lower[NL], upper[NU];  // local copies: kept in registers
    for (int k = 0; k < NL; ++k) lower[k] = lowerIn[k];
    for (int k = 0; k < NU; ++k) upper[k] = upperIn[k];
    const int W = cam_.width;
    Fragment<Scalar> frag;
    frag.face = s.face;
    for (std::int64_t y = rowFirst; y <= rowLast; ++y) {
      std::int64_t lo = std::max<std::int64_t>(0, lower[0].q);
      std::int64_t hi = std::min(jmax, upper[0].q);
      if (NL == 2) lo = std::max(lo, lower[NL - 1].q);
      if (NU == 2) hi = std::min(hi, upper[NU - 1].q);
      if (lo <= hi) {
        if constexpr (kMode == FillMode::Spans) {
          fn(static_cast<int>(y), static_cast<int>(px0 + lo), static_cast<int>(px0 + hi + 1));
        } else {
          const Scalar ys = static_cast<Scalar>(y);
          const Scalar r0 = s.b[0] * ys + s.c[0], r1 = s.b[1] * ys + s.c[1],
                       r2 = s.b[2] * ys + s.c[2], rSum = s.bSum * ys + s.cSum;
          float* drow = kMode == FillMode::PixelsDepth ? depth_->data.data() + y * W : nullptr;
          frag.y = static_cast<int>(y);
          const int xEnd = static_cast<int>(px0 + hi);
          for (int x = static_cast<int>(px0 + lo); x <= xEnd; ++x) {
            const Scalar xs = static_cast<Scalar>(x);
            if constexpr (kMode == FillMode::PixelsDepth) {
              // z < stored ⇔ (1/z)·stored > 1 (both positive): no division for hidden
              // fragments; the stored depth is a float, so divide in float.
              const float invZ = static_cast<float>(s.aSum * xs + rSum);
              if (!(invZ * drow[x] > 1.0f)) continue;  // also rejects NaN
              drow[x] = 1.0f / invZ;
            }
            // Dead code when the functor reads neither barycentrics nor depth.
            frag.x = x;
            frag.q0 = s.a[0] * xs + r0;
            frag.q1 = s.a[1] * xs + r1;
            frag.q2 = s.a[2] * xs + r2;
            fn(static_cast<const Fragment<Scalar>&>(frag));
          }
        }
      }
      for (int k = 0; k < NL; ++k) lower[k].nextLower();
      for (int k = 0; k < NU; ++k) upper[k].nextUpper();
    }
  }

  PinholeCamera<Scalar> cam_;
  RasterOptions<Scalar> opt_;
  render_detail::ClipCamera clip_{};
  Image<float>* depth_ = nullptr;
  std::vector<render_detail::ProjVertex> verts_;
};

}  // namespace hawor
