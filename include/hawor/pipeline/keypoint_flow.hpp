// hawor/pipeline/keypoint_flow.hpp — a hand's keypoints carried to the next frame without the
// landmark network, and the schedule on which the network must run again.
//
// Prediction (per tracked hand, from frame t−1 to t, on grey frames at the SLAM's size):
//   1. corners (Shi–Tomasi, slam/corners.hpp) on the hand in frame t−1: inside the palm polygon
//      (wrist, thumb CMC, the four MCPs) or within `reach` × hand size of a bone;
//   2. pyramidal KLT (slam/klt.hpp, forward–backward checked) into frame t;
//   3. a 2D similarity x' = s R x + t fitted to the tracks by RANSAC (two-point samples, inliers
//      within `inlierShare` × hand size), refined by least squares on the inliers (in complex
//      numbers: a = Σ (z'−m')·conj(z−m) / Σ |z−m|², t = m' − a m);
//   4. the last keypoints moved by it (the articulation is held) and the 3D keypoints rotated by R
//      about the view axis (MediaPipe's world landmarks keep the image's axes).
// Schedule (per hand): a prediction stands in for the network when its tracks agree (enough
// inliers) and the hand has gone fewer than `skip` frames without the network. `skip` adapts to
// how well the flow did: each time the network runs on a hand, the prediction made for that same
// frame is compared with it (median keypoint distance over the hand's size); an error below
// `goodError` lets the next gap be one frame longer (up to maxSkip), one above `badError` halves
// it. Hands whose fingers move fast are thus re-measured every frame, a hand that only moves
// with the head every maxSkip + 1 frames.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/pipeline/sides.hpp"
#include "hawor/render/image.hpp"
#include "hawor/slam/corners.hpp"
#include "hawor/slam/image_pyramid.hpp"
#include "hawor/slam/klt.hpp"
#include "hawor/slam/ransac.hpp"

namespace hawor {

template <typename Scalar>
struct KeypointFlowOptions {
  int maxSkip = 5;                      ///< frames at most between the network's runs on a hand (0: flow off)
  int maxCorners = 48;                  ///< corners tracked per hand
  int minInliers = 6;                   ///< tracks that agree with the similarity, at least
  Scalar minInlierRatio = Scalar(0.5);  ///< and this share of the tracked corners
  Scalar inlierShare = Scalar(0.03);    ///< RANSAC threshold, × hand size (pixels at least 1)
  Scalar reach = Scalar(0.08);          ///< corners within this × hand size of a bone
  Scalar goodError = Scalar(0.08);      ///< prediction error (× hand size) that lengthens the gap
  Scalar badError = Scalar(0.16);       ///< error that halves it
  int pyramidLevels = 3;
  /// The hand mask of a carried hand grows by this × hand size (the prediction's error: fingers
  /// that moved since the network's last run stay masked from the SLAM).
  Scalar maskGrowth = Scalar(0.25);

  void validate() const {
    auto bad = [](const std::string& what) { throw Error("keypoint flow: " + what); };
    if (maxSkip < 0 || maxSkip > 30) bad("maxSkip must be in 0..30, not " + std::to_string(maxSkip));
    if (maxCorners < 4 || maxCorners > 1000) bad("maxCorners must be in 4..1000");
    if (minInliers < 2 || minInliers > maxCorners) bad("minInliers must be in 2..maxCorners");
    if (!(minInlierRatio >= Scalar(0) && minInlierRatio <= Scalar(1))) bad("minInlierRatio must be in [0, 1]");
    if (!(inlierShare > Scalar(0) && inlierShare < Scalar(1))) bad("inlierShare must be in (0, 1)");
    if (!(reach > Scalar(0) && reach < Scalar(1))) bad("reach must be in (0, 1)");
    if (!(goodError > Scalar(0) && goodError < badError)) bad("goodError must be > 0 and below badError");
    if (pyramidLevels < 1 || pyramidLevels > 6) bad("pyramidLevels must be in 1..6");
    if (!(maskGrowth >= Scalar(0) && maskGrowth <= Scalar(1))) bad("maskGrowth must be in [0, 1]");
  }
};

/// One hand's keypoints predicted on the current frame.
template <typename Scalar>
struct KeypointPrediction {
  int track = -1;
  Pixels<Scalar> keypoints2d;   ///< (21, 2), the video's pixels
  Points3<Scalar> keypoints3d;  ///< (21, 3) metres, or empty when the last detection had none
  Scalar pRight = Scalar(0.5);  ///< the last detection's
  int inliers = 0;              ///< corner tracks that agree with the similarity
  Scalar scale = Scalar(1), angle = Scalar(0);  ///< the similarity's
  bool trusted = false;         ///< may stand in for the network on this frame (the schedule)
};

/// 2D similarity z' = a z + b in complex numbers.
template <typename Scalar>
struct Similarity2 {
  std::complex<Scalar> a{Scalar(1), Scalar(0)}, b{Scalar(0), Scalar(0)};
  std::complex<Scalar> operator()(const std::complex<Scalar>& z) const { return a * z + b; }
};

/// Least-squares similarity taking z[i] to w[i] over the indices (at least two distinct points);
/// false when they coincide.
template <typename Scalar>
bool fitSimilarity2(const std::vector<std::complex<Scalar>>& z, const std::vector<std::complex<Scalar>>& w,
                    const int* idx, int n, Similarity2<Scalar>& out) {
  using C = std::complex<Scalar>;
  C mz(0, 0), mw(0, 0);
  for (int k = 0; k < n; ++k) { mz += z[idx[k]]; mw += w[idx[k]]; }
  mz /= Scalar(n);
  mw /= Scalar(n);
  C num(0, 0);
  Scalar den(0);
  for (int k = 0; k < n; ++k) {
    const C dz = z[idx[k]] - mz;
    num += (w[idx[k]] - mw) * std::conj(dz);
    den += std::norm(dz);
  }
  if (!(den > Scalar(1e-12))) return false;
  out.a = num / den;
  out.b = mw - out.a * mz;
  return std::isfinite(out.a.real()) && std::isfinite(out.a.imag()) && std::isfinite(out.b.real()) && std::isfinite(out.b.imag());
}

/// A hand's size in pixels: the larger side of its keypoints' bounding box (over the finite rows:
/// a given hand's keypoints behind the camera are NaN; 0 without any).
template <typename Scalar>
Scalar keypointExtent(const Pixels<Scalar>& kp) {
  Scalar x0 = std::numeric_limits<Scalar>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (Eigen::Index k = 0; k < kp.rows(); ++k) {
    if (!std::isfinite(double(kp(k, 0))) || !std::isfinite(double(kp(k, 1)))) continue;
    x0 = std::min(x0, kp(k, 0)), x1 = std::max(x1, kp(k, 0)), y0 = std::min(y0, kp(k, 1)), y1 = std::max(y1, kp(k, 1));
  }
  return x1 >= x0 ? std::max(x1 - x0, y1 - y0) : Scalar(0);
}

/// The mean of a hand's finite keypoints (pixels; NaN without any).
template <typename Scalar>
Vec2<Scalar> keypointCentre(const Pixels<Scalar>& kp) {
  Vec2<Scalar> c = Vec2<Scalar>::Zero();
  int n = 0;
  for (Eigen::Index k = 0; k < kp.rows(); ++k) {
    if (!std::isfinite(double(kp(k, 0))) || !std::isfinite(double(kp(k, 1)))) continue;
    c += kp.row(k).transpose();
    ++n;
  }
  return n > 0 ? Vec2<Scalar>(c / Scalar(n)) : Vec2<Scalar>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
}

template <typename Scalar>
class KeypointFlow {
 public:
  static constexpr int kNumKeypoints = 21;

  explicit KeypointFlow(const KeypointFlowOptions<Scalar>& o = {}) : opt_(o) { opt_.validate(); }
  const KeypointFlowOptions<Scalar>& options() const { return opt_; }
  bool enabled() const { return opt_.maxSkip > 0; }

  /// The grey frame `index` at the SLAM's size; toFrame: its pixels per video pixel (a video pixel
  /// u is at toFrame·u + (toFrame − 1)/2, pixel centres kept). A frame that does not follow the
  /// last one breaks every hand's continuity.
  void setFrame(const ImageU8& grey, int index, Scalar toFrame) {
    if (grey.channels != 1 || grey.width < 16 || grey.height < 16) throw Error("keypoint flow: expected a grey frame of at least 16 x 16");
    std::swap(prev_, cur_);
    cur_.build(grey, opt_.pyramidLevels);
    const bool follows = index == frame_ + 1 && prev_.numLevels() > 0 && prev_.level(0).width == grey.width &&
                         prev_.level(0).height == grey.height && toFrame == toFrame_;
    if (!follows) hands_.clear();
    frame_ = index;
    toFrame_ = toFrame;
    predictions_.clear();
    predicted_ = false;
  }

  /// The hands of the last frame carried to the current one (after setFrame).
  const std::vector<KeypointPrediction<Scalar>>& predict() {
    if (predicted_) return predictions_;
    predicted_ = true;
    for (const Hand& h : hands_) {
      if (h.frame != frame_ - 1) continue;
      KeypointPrediction<Scalar> p;
      if (!carry(h, p)) continue;
      p.trusted = p.inliers >= opt_.minInliers && h.sinceNetwork < h.skip;
      predictions_.push_back(std::move(p));
    }
    return predictions_;
  }

  /// The current frame's detections as the pipeline took them (HandDetection::flow: a
  /// prediction, not the network's). Updates each hand's schedule.
  void observe(const std::vector<HandDetection<Scalar>>& dets) {
    std::vector<Hand> next;
    for (std::size_t i = 0; i < dets.size(); ++i) {
      const HandDetection<Scalar>& d = dets[i];
      if (d.track < 0 || d.keypoints2d.rows() != kNumKeypoints) continue;
      Hand h;
      const Hand* old = find(d.track);
      if (old) h = *old;
      h.track = d.track;
      h.frame = frame_;
      h.keypoints2d = d.keypoints2d;
      h.keypoints3d = d.keypoints3d;
      h.pRight = d.pRight;
      if (d.flow) {
        h.sinceNetwork += 1;
      } else {
        if (old) adapt(h, d.keypoints2d);
        h.sinceNetwork = 0;
      }
      next.push_back(std::move(h));
    }
    hands_ = std::move(next);
  }

  /// The frames the network may be skipped on next for this track (its schedule; 0 unknown).
  int skipOf(int track) const {
    const Hand* h = find(track);
    return h ? h->skip : 0;
  }

 private:
  struct Hand {
    int track = -1, frame = -1;
    Pixels<Scalar> keypoints2d;
    Points3<Scalar> keypoints3d;
    Scalar pRight = Scalar(0.5);
    int sinceNetwork = 0;
    int skip = 1;  ///< a new hand: the flow may stand in once, then the check decides
  };

  const Hand* find(int track) const {
    for (const Hand& h : hands_) {
      if (h.track == track) return &h;
    }
    return nullptr;
  }

  /// The network ran on h's hand: its error against this frame's prediction sets the next gap.
  void adapt(Hand& h, const Pixels<Scalar>& network) {
    for (const KeypointPrediction<Scalar>& p : predictions_) {
      if (p.track != h.track) continue;
      std::array<Scalar, kNumKeypoints> e{};
      for (int k = 0; k < kNumKeypoints; ++k) e[std::size_t(k)] = (p.keypoints2d.row(k) - network.row(k)).norm();
      std::nth_element(e.begin(), e.begin() + kNumKeypoints / 2, e.end());
      const Scalar err = e[kNumKeypoints / 2] / std::max(keypointExtent(network), Scalar(1));
      if (err < opt_.goodError) h.skip = std::min(opt_.maxSkip, h.skip + 1);
      else if (err > opt_.badError) h.skip /= 2;
      return;
    }
  }

  /// Pixels (at the SLAM's size) near h's skeleton, for its corners: an 8-bit mask of the crop
  /// [x0, x0 + w) × [y0, y0 + h), 255 where no corner may be. Each bone clears its capsule and
  /// the palm polygon its inside, each within its own bounding box.
  void skeletonMask(const std::vector<std::complex<Scalar>>& kp, Scalar size, int x0, int y0, ImageU8& blocked) const {
    using C = std::complex<Scalar>;
    static const int bones[][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {0, 5}, {5, 6}, {6, 7}, {7, 8}, {5, 9}, {9, 10}, {10, 11},
                                   {11, 12}, {9, 13}, {13, 14}, {14, 15}, {15, 16}, {13, 17}, {0, 17}, {17, 18}, {18, 19}, {19, 20}};
    static const int palm[] = {0, 1, 5, 9, 13, 17};
    std::fill(blocked.data.begin(), blocked.data.end(), static_cast<unsigned char>(255));
    const Scalar r = opt_.reach * size, r2 = r * r;
    // the pixels of the box [lo, hi] (crop coordinates, clipped) for which inside(p) holds
    auto clear = [&](C lo, C hi, auto&& inside) {
      const int xa = std::max(0, int(std::floor(lo.real())) - x0), xb = std::min(blocked.width - 1, int(std::ceil(hi.real())) - x0);
      const int ya = std::max(0, int(std::floor(lo.imag())) - y0), yb = std::min(blocked.height - 1, int(std::ceil(hi.imag())) - y0);
      for (int y = ya; y <= yb; ++y) {
        unsigned char* row = blocked.row(y);
        for (int x = xa; x <= xb; ++x) {
          if (row[x] && inside(C(Scalar(x0 + x), Scalar(y0 + y)))) row[x] = 0;
        }
      }
    };
    for (const auto& b : bones) {
      const C a = kp[std::size_t(b[0])], d = kp[std::size_t(b[1])] - a;
      const Scalar len2 = std::norm(d);
      const C lo(std::min(a.real(), a.real() + d.real()) - r, std::min(a.imag(), a.imag() + d.imag()) - r);
      const C hi(std::max(a.real(), a.real() + d.real()) + r, std::max(a.imag(), a.imag() + d.imag()) + r);
      clear(lo, hi, [&](C p) {
        const Scalar t = len2 > Scalar(0) ? std::clamp(((p - a) * std::conj(d)).real() / len2, Scalar(0), Scalar(1)) : Scalar(0);
        return std::norm(p - a - t * d) <= r2;
      });
    }
    C lo = kp[0], hi = kp[0];
    for (int i : palm) {
      const C q = kp[std::size_t(i)];
      lo = C(std::min(lo.real(), q.real()), std::min(lo.imag(), q.imag()));
      hi = C(std::max(hi.real(), q.real()), std::max(hi.imag(), q.imag()));
    }
    clear(lo, hi, [&](C p) {
      // the parity of the crossings of a ray to +x with the polygon's edges
      bool in = false;
      for (int i = 0, j = 5; i < 6; j = i++) {
        const C a = kp[std::size_t(palm[i])], c = kp[std::size_t(palm[j])];
        if ((a.imag() > p.imag()) != (c.imag() > p.imag()) &&
            p.real() < (c.real() - a.real()) * (p.imag() - a.imag()) / (c.imag() - a.imag()) + a.real()) {
          in = !in;
        }
      }
      return in;
    });
  }

  /// Carries hand h from the previous frame to the current one.
  bool carry(const Hand& h, KeypointPrediction<Scalar>& p) {
    using C = std::complex<Scalar>;
    const ImageF& g = prev_.level(0);
    std::vector<C> kp(kNumKeypoints);
    const C off((toFrame_ - Scalar(1)) / Scalar(2), (toFrame_ - Scalar(1)) / Scalar(2));
    for (int k = 0; k < kNumKeypoints; ++k) kp[std::size_t(k)] = C(h.keypoints2d(k, 0), h.keypoints2d(k, 1)) * toFrame_ + off;
    Scalar x0 = kp[0].real(), x1 = x0, y0 = kp[0].imag(), y1 = y0;
    for (const C& z : kp) {
      x0 = std::min(x0, z.real()); x1 = std::max(x1, z.real());
      y0 = std::min(y0, z.imag()); y1 = std::max(y1, z.imag());
    }
    const Scalar size = std::max(x1 - x0, y1 - y0);
    if (!(size >= Scalar(8)) || !std::isfinite(size)) return false;
    // the crop: the hand's box grown by the reach and the corner detector's border
    const CornerOptions co{8, 1, 2.0f, 4, 6, 2};
    const Scalar grow = opt_.reach * size + Scalar(co.border + 1);
    const int cx0 = std::max(0, int(std::floor(x0 - grow))), cy0 = std::max(0, int(std::floor(y0 - grow)));
    const int cx1 = std::min(g.width, int(std::ceil(x1 + grow)) + 1), cy1 = std::min(g.height, int(std::ceil(y1 + grow)) + 1);
    if (cx1 - cx0 < 2 * co.border + 3 || cy1 - cy0 < 2 * co.border + 3) return false;
    crop_.resize(cx1 - cx0, cy1 - cy0, 1);
    for (int y = 0; y < crop_.height; ++y) std::copy_n(g.row(cy0 + y) + cx0, crop_.width, crop_.row(y));
    blocked_.resize(crop_.width, crop_.height, 1);
    skeletonMask(kp, size, cx0, cy0, blocked_);
    std::vector<std::array<float, 2>> corners, none;
    detectCorners(crop_, &blocked_, none, opt_.maxCorners, co, corners, scratch_);
    if (int(corners.size()) < opt_.minInliers) return false;
    for (auto& c : corners) { c[0] += float(cx0); c[1] += float(cy0); }
    std::vector<std::array<float, 2>> to = corners;
    std::vector<char> ok;
    trackKlt(prev_, cur_, corners, to, ok);
    std::vector<C> from, dest;
    for (std::size_t i = 0; i < corners.size(); ++i) {
      if (!ok[i]) continue;
      from.emplace_back(Scalar(corners[i][0]), Scalar(corners[i][1]));
      dest.emplace_back(Scalar(to[i][0]), Scalar(to[i][1]));
    }
    const int n = static_cast<int>(from.size());
    if (n < opt_.minInliers) return false;
    RansacOptions<Scalar> ro;
    ro.threshold = std::max(Scalar(1), opt_.inlierShare * size);
    ro.maxIterations = 200;
    auto solve = [&](const int* s, std::vector<Similarity2<Scalar>>& models) {
      Similarity2<Scalar> m;
      if (fitSimilarity2(from, dest, s, 2, m)) models.push_back(m);
    };
    auto err2 = [&](const Similarity2<Scalar>& m, int i) { return std::norm(m(from[std::size_t(i)]) - dest[std::size_t(i)]); };
    const auto rr = ransac<Similarity2<Scalar>, Scalar>(n, 2, solve, err2, ro);
    if (!rr.found) return false;
    std::vector<int> inl;
    for (int i = 0; i < n; ++i) {
      if (rr.inliers[std::size_t(i)]) inl.push_back(i);
    }
    Similarity2<Scalar> m = rr.model;
    if (int(inl.size()) >= 2) fitSimilarity2(from, dest, inl.data(), int(inl.size()), m);
    p.track = h.track;
    p.pRight = h.pRight;
    p.inliers = Scalar(inl.size()) >= opt_.minInlierRatio * Scalar(n) ? int(inl.size()) : 0;
    p.scale = std::abs(m.a);
    p.angle = std::arg(m.a);
    // the similarity in the video's pixels: u' = a u + (a·off + b − off) / toFrame
    p.keypoints2d.resize(kNumKeypoints, 2);
    const C bVideo = (m.a * off + m.b - off) / toFrame_;
    for (int k = 0; k < kNumKeypoints; ++k) {
      const C z = m.a * C(h.keypoints2d(k, 0), h.keypoints2d(k, 1)) + bVideo;
      p.keypoints2d(k, 0) = z.real();
      p.keypoints2d(k, 1) = z.imag();
    }
    p.keypoints3d = h.keypoints3d;
    if (p.keypoints3d.rows() == kNumKeypoints) {
      // rotation about the view axis (z): image x right, y down
      const Scalar c = std::cos(p.angle), s = std::sin(p.angle);
      for (int k = 0; k < kNumKeypoints; ++k) {
        const Scalar x = h.keypoints3d(k, 0), y = h.keypoints3d(k, 1);
        p.keypoints3d(k, 0) = c * x - s * y;
        p.keypoints3d(k, 1) = s * x + c * y;
      }
    }
    return true;
  }

  KeypointFlowOptions<Scalar> opt_;
  ImagePyramid prev_, cur_;
  int frame_ = -2;
  Scalar toFrame_ = Scalar(1);
  std::vector<Hand> hands_;
  std::vector<KeypointPrediction<Scalar>> predictions_;
  bool predicted_ = false;
  ImageF crop_;
  ImageU8 blocked_;
  CornerScratch scratch_;
};

}  // namespace hawor
