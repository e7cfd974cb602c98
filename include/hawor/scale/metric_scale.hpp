// hawor/scale/metric_scale.hpp — the whole metric-scale step of one clip as one call (what
// `hawor scale` does, for callers that hold the data in memory: the WebAssembly core, the app):
//   depth cue   the keyframes' sparse SLAM depths paired with metric depth maps at the same
//               pixels (nearest pixel: u, v rounded; pixels outside the map dropped), hand pixels
//               flagged from the keyframes' masks, then AdaSM over keyframes (robust_scale.hpp);
//   hand cue    the hand-anchored scale from camera-frame metric hand positions (hand_scale.hpp);
//   ground cue  the cameras' height above the floor plane of the SLAM map (ground_scale.hpp);
//   fusion      the two cues that need no depth network (hands, ground) first: a floor reading
//               that could be a table top (ambiguous) takes whichever reading is nearer the hands'
//               scale, then both are averaged in log space weighted by confidence; that result
//               and the depth cue are fused the same way (fuse_scale.hpp).
// Any cue may be absent. Defaults are those of `hawor scale`: SLAM-depth sampling with 30
// points per window, Huber combination over keyframes, hold windows of half a second.
// Thread-safety: pure functions.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/scale/fuse_scale.hpp"
#include "hawor/scale/ground_scale.hpp"
#include "hawor/scale/hand_scale.hpp"
#include "hawor/scale/robust_scale.hpp"

namespace hawor {

template <typename Scalar>
struct MetricScaleOptions {
  AdaptiveScaleOptions<Scalar> depth;
  HandScaleOptions<Scalar> hands;
  GroundScaleOptions<Scalar> ground;
  MetricScaleOptions() {
    // Sparse SLAM depths: the official D-window truncates the noise (robust_scale.hpp), and a
    // window of 10 points is too noisy.
    depth.sampling = AdaSmSampling::SlamDepth;
    depth.minPixels = 30;
    depth.combine = KeyframeCombine::Huber;
  }
  /// Frame rate of the clip: the smoothness cue's time step and hold windows of half a second.
  void setFps(Scalar fps) {
    if (!(fps > Scalar(0)) || !std::isfinite(double(fps))) throw Error("metric scale: fps must be > 0");
    hands.smoothness.fps = fps;
    hands.hold.window = std::max(5, static_cast<int>(std::lround(0.5 * double(fps))));
  }
};

/// One keyframe's pairs for AdaSM.
template <typename Scalar>
struct KeyframeDepthPairs {
  std::vector<Scalar> slam, metric;
  std::vector<char> masked;
};

/// Pairs n sparse SLAM depths at pixels uv (2n, u then v) with a metric depth map (W×H row-major,
/// metres, non-finite = unknown) at the nearest pixel; `mask` (W×H, may be null) flags hand
/// pixels. Pixels outside the map are dropped. Throws for a bad size or a non-finite pixel.
template <typename Scalar, typename DepthT>
KeyframeDepthPairs<Scalar> pairKeyframeDepths(const Scalar* uv, const Scalar* slamDepth, std::size_t n,
                                              const DepthT* map, int W, int H, const std::uint8_t* mask = nullptr) {
  if (W <= 0 || H <= 0 || !map) throw Error("metric scale: empty depth map");
  KeyframeDepthPairs<Scalar> out;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(double(uv[2 * i])) || !std::isfinite(double(uv[2 * i + 1]))) {
      throw Error("metric scale: keyframe pixel " + std::to_string(i) + " is not finite");
    }
    const long x = std::lround(double(uv[2 * i])), y = std::lround(double(uv[2 * i + 1]));
    if (x < 0 || y < 0 || x >= W || y >= H) continue;
    const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
    out.slam.push_back(slamDepth[i]);
    out.metric.push_back(Scalar(map[p]));
    out.masked.push_back(mask && mask[p] ? 1 : 0);
  }
  return out;
}

template <typename Scalar>
struct MetricScaleResult {
  FusedScale<Scalar> fused;         ///< the answer (not ok() when neither cue gave a scale)
  bool depthRan = false, handsRan = false, groundRan = false;
  SequenceScale<Scalar> depth;      ///< the depth cue (when it ran)
  Scalar depthConfidence = Scalar(0);
  HandScaleResult<Scalar> hands;    ///< the hand cue (when it ran)
  GroundScaleResult<Scalar> ground; ///< the ground cue (when it ran)
  Scalar groundUsed = std::numeric_limits<Scalar>::quiet_NaN();  ///< the ground reading fused
  FusedScale<Scalar> noDepth;       ///< hands and ground combined (the cues without a depth network)
};

/// The metric scale (file comment). `keyframes` may be empty (no depth maps); `hands` may be
/// empty (no hand cue; otherwise one track per hand, each as long as T_w_c); `mapPoints` (world
/// frame, map units) null or empty for no ground cue. Throws for mismatched lengths or invalid
/// options; an absent answer is fused.ok() == false.
template <typename Scalar>
MetricScaleResult<Scalar> estimateMetricScale(const std::vector<KeyframeDepthPairs<Scalar>>& keyframes,
                                              const std::vector<SE3<Scalar>>& T_w_c,
                                              const std::vector<HandTrack<Scalar>>& hands,
                                              const MetricScaleOptions<Scalar>& opt = {},
                                              const std::vector<Vec3<Scalar>>* mapPoints = nullptr) {
  MetricScaleResult<Scalar> r;
  Scalar ds = std::numeric_limits<Scalar>::quiet_NaN(), hs = ds, hc = Scalar(0);
  if (!keyframes.empty()) {
    std::vector<std::vector<Scalar>> d, D;
    std::vector<std::vector<char>> m;
    for (const auto& k : keyframes) {
      if (k.slam.size() != k.metric.size() || k.masked.size() != k.slam.size()) {
        throw Error("metric scale: a keyframe's SLAM depths, metric depths and hand flags differ in length");
      }
      d.push_back(k.slam), D.push_back(k.metric), m.push_back(k.masked);
    }
    r.depth = adaptiveScale(d, D, &m, opt.depth);
    r.depthRan = true;
    if (r.depth.ok()) {
      ds = r.depth.scale;
      r.depthConfidence = depthScaleConfidence(r.depth);
    }
  }
  if (!hands.empty()) {
    r.hands = handAnchoredScale(T_w_c, hands, opt.hands);
    r.handsRan = true;
    if (r.hands.ok()) hs = r.hands.scale, hc = r.hands.confidence;
  }
  Scalar gs = std::numeric_limits<Scalar>::quiet_NaN(), gc = Scalar(0);
  if (mapPoints && !mapPoints->empty()) {
    r.ground = groundPlaneScale(*mapPoints, T_w_c, opt.ground);
    r.groundRan = true;
    if (r.ground.ok()) {
      gs = groundReadingNear(r.ground, hs, hc);  // floor or table top: the one the hands agree with
      gc = r.ground.confidence;
      r.groundUsed = gs;
    }
  }
  r.noDepth = fuseScaleCues<Scalar>({{hs, hc, "hands"}, {gs, gc, "ground"}});
  r.fused = fuseScaleCues<Scalar>({{ds, r.depthConfidence, "depth"}, {r.noDepth.scale, r.noDepth.confidence, r.noDepth.method}});
  return r;
}

}  // namespace hawor
