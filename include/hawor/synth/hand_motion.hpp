// hawor/synth/hand_motion.hpp — hand-like motion of one hand in front of an egocentric camera.
//
// A HandPlan is a list of keys in the HEAD frame: the camera frame of a head orientation that
// follows the real camera with a lag (sequence.hpp: an exponential smoothing of the camera's
// rotation with time constant HandBehaviour::lagSeconds, about the camera centre). Hands are
// held relative to the body, not glued to the camera: after a fast head turn they trail
// behind and leave the view, as real hands do. Coordinates are OpenCV's (x right, y down,
// z forward; metres); x is mirrored by the side (+1 right hand, −1 left hand).
//
// Phases alternate at random (a hand that has been in view for maxInView seconds leaves at the
// end of its phase): IN VIEW (the wrist 0.2–0.5 m in front, below and to the hand's side of
// the optical axis; a new target every 0.5–1.2 s), and OUT OF VIEW (the wrist dropped
// below the image: y 0.45–0.6 m, z 0.15–0.3 m, so the hand enters and leaves through the bottom
// edge as in egocentric video). Per key: wrist position, a finger direction and palm normal
// (randomOrientation: fingers forward with some pronation / supination, or fingers up with the
// palm or the back of the hand towards the camera), and a gesture (open, relaxed, grasp, point,
// pinch). Between keys: Catmull–Rom for the wrist, normalised quaternion interpolation with a
// smoothstep weight for the orientation, and smoothstep for the gesture; plus small B-spline
// jitters so that a hand never freezes.
// The two hands use independent random streams: they move independently.
// Thread-safety: a built plan is read-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/synth/hand_rig.hpp"
#include "hawor/synth/random.hpp"

namespace hawor {
namespace synth {

/// How a preset's hands behave (times in seconds, distances in metres, head frame).
struct HandBehaviour {
  double inViewChance = 0.7;            ///< probability that the next phase is in view
  double inViewMin = 1.5, inViewMax = 3.5;
  double outMin = 0.6, outMax = 2.0;
  double depthMin = 0.22, depthMax = 0.42;  ///< wrist z when in view
  double lateralMin = 0.03, lateralMax = 0.2;  ///< wrist |x|, towards the hand's own side
  double heightMin = 0.05, heightMax = 0.2;    ///< wrist y (down)
  double palmToCamera = 0.08;           ///< chance of a key showing the palm to the camera
  double backToCamera = 0.1;            ///< chance of fingers up with the back of the hand to the camera
  double fingerUpMin = 0.5, fingerUpMax = 1.4;  ///< finger direction (−up, forward) = (f, 1): tilt up in the image
  double lagSeconds = 0.25;             ///< time constant of the head frame (sequence.hpp)
  double moveMin = 0.5, moveMax = 1.2;  ///< time between targets inside a phase
  double startInView = 0.7;             ///< probability that a hand starts in view
  double maxInView = 6.0;               ///< longest continuous stay in view; then the hand leaves
  /// The body the hands hang from follows the camera centre smoothed by a Gaussian of this
  /// standard deviation (s): it shares the head's walk but not its bob, sway, jitter and the
  /// lever arm of the neck (sequence.hpp). 0 glues the hands to the camera centre.
  double bodySmoothSeconds = 0.3;
  /// Holds: after an in-view key, with this chance the hand stays still IN THE ROOM (holding or
  /// resting on something) for holdMin–holdMax seconds, eased in and out over holdEase seconds.
  double holdChance = 0.0;
  double holdMin = 0.6, holdMax = 1.6, holdEase = 0.25;
};

/// A hold of one hand: the wrist and its orientation stay fixed in the room over [t0, t1].
struct HandHold {
  double t0 = 0, t1 = 0;
};

/// One key of a hand plan (head frame).
template <typename Scalar>
struct HandKey {
  double t = 0;
  Vec3<Scalar> wrist = Vec3<Scalar>::Zero();
  Eigen::Quaternion<Scalar, Eigen::DontAlign> orient{Eigen::Quaternion<Scalar, Eigen::DontAlign>::Identity()};
  Gesture<Scalar> gesture;
  bool inView = true;
};

/// The hand's state at one time, head frame.
template <typename Scalar>
struct HandState {
  Vec3<Scalar> wrist = Vec3<Scalar>::Zero();
  Mat3<Scalar> R = Mat3<Scalar>::Identity();  ///< global orientation (model → head frame)
  Gesture<Scalar> gesture;
};

template <typename Scalar>
class HandPlan {
 public:
  std::vector<HandKey<Scalar>> keys;
  std::vector<HandHold> holds;  ///< in time order, disjoint (applied in the room by sequence.hpp)
  SmoothSignal<Scalar> posJitter, rotJitter, curlJitter;

  /// State at time t (clamped to the keys' span).
  HandState<Scalar> at(double t) const {
    if (keys.empty()) throw Error("HandPlan: no keys");
    HandState<Scalar> s;
    const std::size_t n = keys.size();
    std::size_t i = 0;
    Scalar u = Scalar(0);
    if (n > 1 && t > keys.front().t) {
      if (t >= keys.back().t) {
        i = n - 2;
        u = Scalar(1);
      } else {
        i = static_cast<std::size_t>(std::upper_bound(keys.begin(), keys.end(), t,
                                                      [](double v, const HandKey<Scalar>& k) { return v < k.t; }) -
                                     keys.begin() - 1);
        u = Scalar((t - keys[i].t) / (keys[i + 1].t - keys[i].t));
      }
    }
    if (n == 1) {
      s.wrist = keys[0].wrist;
      s.R = keys[0].orient.toRotationMatrix();
      s.gesture = keys[0].gesture;
    } else {
      // Catmull–Rom (non-uniform, finite-difference tangents) for the wrist.
      const HandKey<Scalar>& a = keys[i];
      const HandKey<Scalar>& b = keys[i + 1];
      const double dt = b.t - a.t;
      auto tangent = [&](std::size_t k) -> Vec3<Scalar> {
        if (k == 0 || k + 1 >= n) return Vec3<Scalar>::Zero();
        return Vec3<Scalar>((keys[k + 1].wrist - keys[k - 1].wrist) * Scalar(dt / (keys[k + 1].t - keys[k - 1].t)));
      };
      const Scalar s2 = u * u, s3 = s2 * u;
      s.wrist = (2 * s3 - 3 * s2 + 1) * a.wrist + (s3 - 2 * s2 + u) * tangent(i) + (-2 * s3 + 3 * s2) * b.wrist +
                (s3 - s2) * tangent(i + 1);
      const Scalar w = smoothstep(u);
      Eigen::Quaternion<Scalar> qa(a.orient), qb(b.orient);
      if (qa.dot(qb) < Scalar(0)) qb.coeffs() = -qb.coeffs();
      Eigen::Quaternion<Scalar> q;
      q.coeffs() = (Scalar(1) - w) * qa.coeffs() + w * qb.coeffs();
      q.normalize();
      s.R = q.toRotationMatrix();
      s.gesture = Gesture<Scalar>::lerp(a.gesture, b.gesture, w);
    }
    if (posJitter.dims() >= 3) s.wrist += posJitter.vec3(t);
    if (rotJitter.dims() >= 3) s.R = Mat3<Scalar>(axisAngleToMatrix(rotJitter.vec3(t)) * s.R);
    if (curlJitter.dims() >= 5) {
      for (int f = 0; f < 5; ++f) s.gesture.curl[static_cast<std::size_t>(f)] += curlJitter(t, f);
    }
    return s;
  }
};

namespace hand_motion_detail {

/// A random gesture: open, relaxed, grasp, point or pinch.
template <typename Scalar>
Gesture<Scalar> randomGesture(SynthRng& rng) {
  Gesture<Scalar> g;
  const double r = rng.uniform();
  auto set = [&](double lo, double hi) {
    for (auto& c : g.curl) c = Scalar(rng.uniform(lo, hi));
  };
  if (r < 0.25) {
    set(0.0, 0.2);  // open
  } else if (r < 0.55) {
    set(0.25, 0.5);  // relaxed
  } else if (r < 0.8) {
    set(0.55, 0.9);  // grasp
  } else if (r < 0.9) {
    set(0.7, 0.95);  // point: index straight
    g.curl[1] = Scalar(rng.uniform(0.0, 0.1));
    g.curl[0] = Scalar(rng.uniform(0.4, 0.7));
  } else {
    set(0.2, 0.6);  // pinch: thumb and index half closed
    g.curl[0] = g.curl[1] = Scalar(rng.uniform(0.5, 0.65));
  }
  g.spread = Scalar(rng.uniform(-0.6, 0.8));
  return g;
}

/// Orientation of a key (head frame) for the hand on `side` (+1 right, −1 left): one of
///   palm to camera   fingers up, the palm towards the camera (−z)
///   back to camera   fingers up, the back of the hand towards the camera
///   forward          fingers forward and up in the image, the back of the hand towards the
///                    camera, then a turn ψ about the finger direction (ψ > 0 turns the palm
///                    towards the image centre)
template <typename Scalar>
Eigen::Quaternion<Scalar> randomOrientation(const HandRig<Scalar>& rig, const HandBehaviour& b, double side,
                                            bool allowFrontal, SynthRng& rng) {
  Vec3<Scalar> A, N;
  const double r = rng.uniform();
  if (allowFrontal && r < b.palmToCamera + b.backToCamera) {
    // (One draw per statement: the order of evaluation of function arguments is unspecified, and
    // compilers differ, so several draws in one call would differ between platforms.)
    const double ax = -side * rng.uniform(0.0, 0.35);
    const double az = rng.uniform(0.1, 0.5);
    A = Vec3<Scalar>(Scalar(ax), Scalar(-1), Scalar(az));
    const Scalar towards = r < b.palmToCamera ? Scalar(-1) : Scalar(1);
    const double nx = side * rng.uniform(-0.2, 0.2);
    const double ny = rng.uniform(-0.1, 0.2);
    N = Vec3<Scalar>(Scalar(nx), Scalar(ny), towards);
  } else {
    const double ax = -side * rng.uniform(0.05, 0.4);
    const double ay = -rng.uniform(b.fingerUpMin, b.fingerUpMax);
    A = Vec3<Scalar>(Scalar(ax), Scalar(ay), Scalar(1));
    A.normalize();
    Vec3<Scalar> N0(0, 1, 0);
    N0 = (N0 - N0.dot(A) * A).normalized();
    const double psi = side * rng.uniform(-0.35, 1.0);
    N = Mat3<Scalar>(axisAngleToMatrix(Vec3<Scalar>(A * Scalar(psi)))) * N0;
  }
  const Mat3<Scalar> R = rig.orientation(A, N);
  return matrixToQuaternion(R);
}

}  // namespace hand_motion_detail

/// The plan of one hand over [0, duration]: side +1 (right) or −1 (left).
template <typename Scalar>
HandPlan<Scalar> makeHandPlan(const HandRig<Scalar>& rig, const HandBehaviour& b, double side, double duration,
                              SynthRng& rng) {
  using namespace hand_motion_detail;
  if (!(duration > 0)) throw Error("makeHandPlan: duration must be > 0");
  HandPlan<Scalar> plan;
  bool inView = rng.chance(b.startInView);
  double t = 0;
  auto inKey = [&](double time) {
    HandKey<Scalar> k;
    k.t = time;
    const double x = side * rng.uniform(b.lateralMin, b.lateralMax);
    const double y = rng.uniform(b.heightMin, b.heightMax);
    const double z = rng.uniform(b.depthMin, b.depthMax);
    k.wrist = Vec3<Scalar>(Scalar(x), Scalar(y), Scalar(z));
    k.orient = randomOrientation(rig, b, side, true, rng);
    k.gesture = randomGesture<Scalar>(rng);
    k.inView = true;
    return k;
  };
  auto outKey = [&](double time) {
    HandKey<Scalar> k;
    k.t = time;
    const double x = side * rng.uniform(0.1, 0.3);
    const double y = rng.uniform(0.45, 0.6);
    const double z = rng.uniform(0.15, 0.3);
    k.wrist = Vec3<Scalar>(Scalar(x), Scalar(y), Scalar(z));
    k.orient = randomOrientation(rig, b, side, false, rng);
    k.gesture = randomGesture<Scalar>(rng);
    k.inView = false;
    return k;
  };
  double inSince = 0;  // start of the current continuous stay in view
  while (t <= duration + 1.0) {
    if (inView) {
      const double end = t + rng.uniform(b.inViewMin, b.inViewMax);
      while (t < end) {
        plan.keys.push_back(inKey(t));
        if (b.holdChance > 0 && rng.chance(b.holdChance)) {
          // The same key again after the hold: the head-frame path pauses, the room-frame
          // freeze is applied by the sequence.
          const double h = rng.uniform(b.holdMin, b.holdMax);
          plan.holds.push_back({t, t + h});
          HandKey<Scalar> k = plan.keys.back();
          k.t = t + h;
          plan.keys.push_back(k);
          t += h;
        }
        t += rng.uniform(b.moveMin, b.moveMax);
      }
    } else {
      const double end = t + rng.uniform(b.outMin, b.outMax);
      plan.keys.push_back(outKey(t));
      t = std::max(end, t + 0.4);
      plan.keys.push_back(outKey(t));
    }
    t += rng.uniform(0.3, 0.6);  // transition between phases
    const bool wasInView = inView;
    inView = rng.chance(b.inViewChance) && !(wasInView && t - inSince >= b.maxInView);
    if (inView && !wasInView) inSince = t;
  }
  plan.posJitter = SmoothSignal<Scalar>(rng, duration, 0.35, 3, VecX<Scalar>::Constant(3, Scalar(0.006)));
  plan.rotJitter = SmoothSignal<Scalar>(rng, duration, 0.4, 3, VecX<Scalar>::Constant(3, Scalar(0.05)));
  plan.curlJitter = SmoothSignal<Scalar>(rng, duration, 0.3, 5, VecX<Scalar>::Constant(5, Scalar(0.05)));
  return plan;
}

}  // namespace synth
}  // namespace hawor
