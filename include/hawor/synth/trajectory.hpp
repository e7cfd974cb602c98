// hawor/synth/trajectory.hpp — head-like camera trajectories through the room of scene.hpp.
//
// A CameraPath is a list of keys (time, eye position, yaw, pitch, roll) interpolated by cubic
// Hermite segments: at a key marked `stop` the velocity is zero (fixations and the ends of fast
// turns), elsewhere the tangent is the Catmull–Rom finite difference over the neighbouring keys
// (smooth walking and looking around). On top come smooth random jitters (B-splines, random.hpp)
// of the eye and of the angles, a walking bob, and a neck offset: the eye sits `neckOffset`
// metres in front of the rotation axis of the head, so a head turn also moves the camera (as a
// real head does; 0 gives a pure rotation).
//
// Orientation from the angles (room frame of scene.hpp: z up): forward
// f = (cos p·cos y, cos p·sin y, sin p) (yaw y about +z from +x, pitch p up from the horizontal),
// right r0 = normalise(f × z), down d0 = f × r0, then roll ρ about f: r = cos ρ·r0 + sin ρ·d0,
// d = f × r. The camera-to-room rotation has columns (r, d, f): the OpenCV camera frame (docs/design.md §2,
// x right, y down, z forward). Pitch is kept inside (−80°, 80°), so f never meets the vertical.
//
// makeCameraPath() builds the paths of the presets:
//   Walk          a loop around the table at 0.8–1.1 m/s, eye 1.55–1.7 m, looking ahead and a
//                 little down, glancing aside now and then, with a walking bob
//   TableWork     standing at one side of the table, looking down at it (pitch −40° … −65°),
//                 small sway, the odd glance up and a side step
//   FastTurns     standing; fixations of 0.6–1.4 s joined by head turns of 60°–150° in
//                 0.4–0.7 s (smoothstep profile: peaks of 130–560 °/s)
//   PureRotation  the eye fixed (millimetre jitter only, no neck offset); smooth looking around
// Thread-safety: a built path is read-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/scene.hpp"

namespace hawor {
namespace synth {

enum class CameraMotion { Walk, TableWork, FastTurns, PureRotation };

/// One key of a camera path: time (s), eye (room frame, m), yaw / pitch / roll (rad).
template <typename Scalar>
struct CameraKey {
  double t = 0;
  Vec3<Scalar> eye = Vec3<Scalar>::Zero();
  Scalar yaw = Scalar(0), pitch = Scalar(0), roll = Scalar(0);
  bool stop = false;  ///< zero velocity at this key
};

/// A rigid pose as rotation and translation (p ↦ R·p + t).
template <typename Scalar>
struct RigidPose {
  Mat3<Scalar> R = Mat3<Scalar>::Identity();
  Vec3<Scalar> t = Vec3<Scalar>::Zero();
  Vec3<Scalar> operator*(const Vec3<Scalar>& p) const { return R * p + t; }
  RigidPose operator*(const RigidPose& o) const { return {Mat3<Scalar>(R * o.R), Vec3<Scalar>(R * o.t + t)}; }
  RigidPose inverse() const {
    const Mat3<Scalar> Rt = R.transpose();
    return {Rt, Vec3<Scalar>(-(Rt * t))};
  }
};

/// Camera-to-room rotation of the file comment for yaw, pitch, roll.
template <typename Scalar>
Mat3<Scalar> lookRotation(Scalar yaw, Scalar pitch, Scalar roll) {
  using std::cos;
  using std::sin;
  const Vec3<Scalar> f(cos(pitch) * cos(yaw), cos(pitch) * sin(yaw), sin(pitch));
  const Vec3<Scalar> r0 = f.cross(Vec3<Scalar>::UnitZ()).normalized();
  const Vec3<Scalar> d0 = f.cross(r0);
  const Vec3<Scalar> r = cos(roll) * r0 + sin(roll) * d0;
  const Vec3<Scalar> d = f.cross(r);
  Mat3<Scalar> R;
  R.col(0) = r;
  R.col(1) = d;
  R.col(2) = f;
  return R;
}

template <typename Scalar>
class CameraPath {
 public:
  std::vector<CameraKey<Scalar>> keys;  ///< strictly increasing times
  SmoothSignal<Scalar> eyeJitter;       ///< 3 components (m), room frame
  SmoothSignal<Scalar> angleJitter;     ///< yaw, pitch, roll (rad)
  Scalar neckOffset = Scalar(0);        ///< eye in front of the head's vertical axis (m)
  Scalar bobAmplitude = Scalar(0);      ///< vertical walking bob (m); sideways sway is half
  Scalar stepFrequency = Scalar(1.8);   ///< steps per second

  /// Camera-to-room pose at time t (clamped to the keys' span).
  RigidPose<Scalar> at(double t) const {
    if (keys.empty()) throw Error("CameraPath: no keys");
    Vec3<Scalar> eye;
    Scalar yaw, pitch, roll;
    interpolate(t, eye, yaw, pitch, roll);
    if (angleJitter.dims() >= 3) {
      yaw += angleJitter(t, 0);
      pitch += angleJitter(t, 1);
      roll += angleJitter(t, 2);
    }
    const Scalar lim = Scalar(1.39);  // ±80°
    pitch = std::max(-lim, std::min(lim, pitch));
    RigidPose<Scalar> P;
    P.R = lookRotation(yaw, pitch, roll);
    // Neck: the eye moves on a circle about the head's axis as the head turns.
    Vec3<Scalar> horiz(std::cos(yaw), std::sin(yaw), Scalar(0));
    eye += neckOffset * horiz;
    if (eyeJitter.dims() >= 3) eye += eyeJitter.vec3(t);
    if (bobAmplitude > Scalar(0)) {
      const Scalar w = Scalar(2 * 3.14159265358979323846) * stepFrequency * Scalar(t);
      eye.z() += bobAmplitude * std::sin(w);
      const Vec3<Scalar> side(-horiz.y(), horiz.x(), Scalar(0));
      eye += Scalar(0.5) * bobAmplitude * std::sin(Scalar(0.5) * w) * side;
    }
    P.t = eye;
    return P;
  }

 private:
  // Tangent of one channel at key k (per unit of the segment parameter, segment length dt):
  // zero at stop keys and at the ends, else the Catmull–Rom difference.
  template <typename Get>
  auto tangent(std::size_t k, double dt, Get get) const -> decltype(get(keys[0])) {
    using T = decltype(get(keys[0]));
    if (keys[k].stop || k == 0 || k + 1 == keys.size()) return T(get(keys[k]) * Scalar(0));
    const double span = keys[k + 1].t - keys[k - 1].t;
    return T((get(keys[k + 1]) - get(keys[k - 1])) * Scalar(dt / span));
  }
  // Hermite blend of one channel on segment [i, i + 1] with basis weights w.
  template <typename Get>
  auto blend(std::size_t i, double dt, const Scalar (&w)[4], Get get) const -> decltype(get(keys[0])) {
    using T = decltype(get(keys[0]));
    return T(w[0] * get(keys[i]) + w[1] * tangent(i, dt, get) + w[2] * get(keys[i + 1]) + w[3] * tangent(i + 1, dt, get));
  }

  // Hermite interpolation of eye and angles between the keys around t (see the file comment).
  void interpolate(double t, Vec3<Scalar>& eye, Scalar& yaw, Scalar& pitch, Scalar& roll) const {
    const std::size_t n = keys.size();
    if (n == 1 || t <= keys.front().t) {
      const CameraKey<Scalar>& k = keys.front();
      eye = k.eye, yaw = k.yaw, pitch = k.pitch, roll = k.roll;
      return;
    }
    if (t >= keys.back().t) {
      const CameraKey<Scalar>& k = keys.back();
      eye = k.eye, yaw = k.yaw, pitch = k.pitch, roll = k.roll;
      return;
    }
    const std::size_t i = static_cast<std::size_t>(
        std::upper_bound(keys.begin(), keys.end(), t, [](double v, const CameraKey<Scalar>& k) { return v < k.t; }) -
        keys.begin() - 1);
    const double dt = keys[i + 1].t - keys[i].t;
    const Scalar s = Scalar((t - keys[i].t) / dt);
    const Scalar s2 = s * s, s3 = s2 * s;
    const Scalar h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    const Scalar w[4] = {h00, h10, h01, h11};
    eye = blend(i, dt, w, [](const CameraKey<Scalar>& k) { return Vec3<Scalar>(k.eye); });
    yaw = blend(i, dt, w, [](const CameraKey<Scalar>& k) { return k.yaw; });
    pitch = blend(i, dt, w, [](const CameraKey<Scalar>& k) { return k.pitch; });
    roll = blend(i, dt, w, [](const CameraKey<Scalar>& k) { return k.roll; });
  }
};

namespace trajectory_detail {

constexpr double kPi = 3.14159265358979323846;
inline double deg(double d) { return d * kPi / 180.0; }

/// Adds jitter signals scaled by `eyeSigma` (m) and `angleSigma` (rad).
template <typename Scalar>
void addJitter(CameraPath<Scalar>& p, SynthRng& rng, double duration, double eyeSigma, double angleSigma) {
  p.eyeJitter = SmoothSignal<Scalar>(rng, duration, 0.45, 3, VecX<Scalar>::Constant(3, Scalar(eyeSigma)));
  VecX<Scalar> a(3);
  a << Scalar(angleSigma), Scalar(angleSigma), Scalar(angleSigma * 0.5);
  p.angleJitter = SmoothSignal<Scalar>(rng, duration, 0.3, 3, a);
}

}  // namespace trajectory_detail

/// The camera path of a motion kind through `layout`, covering [0, duration] seconds.
template <typename Scalar>
CameraPath<Scalar> makeCameraPath(CameraMotion motion, const RoomLayout<Scalar>& layout, double duration,
                                  SynthRng& rng) {
  using namespace trajectory_detail;
  using V3 = Vec3<Scalar>;
  using S = Scalar;
  if (!(duration > 0)) throw Error("makeCameraPath: duration must be > 0");
  CameraPath<Scalar> path;
  const double eyeHeight = rng.uniform(1.55, 1.7);
  switch (motion) {
    case CameraMotion::Walk: {
      // Waypoints along the loop every ~0.7 m, corners cut by 0.6 m (Catmull–Rom rounds them).
      std::vector<Vec2<Scalar>> loop = layout.walkLoop;
      if (loop.size() < 3) throw Error("makeCameraPath: the layout has no walking loop");
      if (rng.chance(0.5)) std::reverse(loop.begin(), loop.end());
      std::rotate(loop.begin(), loop.begin() + rng.index(static_cast<int>(loop.size())), loop.end());
      std::vector<Vec2<Scalar>> pts;
      const std::size_t m = loop.size();
      for (std::size_t c = 0; c < m; ++c) {
        const Vec2<Scalar> a = loop[c], b = loop[(c + 1) % m];
        const double len = static_cast<double>((b - a).norm());
        const double cut = std::min(0.6, len / 3);
        const int steps = std::max(1, static_cast<int>((len - 2 * cut) / 0.7));
        for (int k = 0; k <= steps; ++k) {
          const double u = (cut + (len - 2 * cut) * k / steps) / len;
          pts.push_back(Vec2<Scalar>(a + S(u) * (b - a)));
        }
      }
      const double speed = rng.uniform(0.8, 1.1);
      double t = 0, yawPrev = 0;
      const double pitchBase = deg(rng.uniform(-24, -12));
      double glanceUntil = -1, glance = 0;
      for (std::size_t k = 0; t <= duration + 2.0; ++k) {
        const Vec2<Scalar> p = pts[k % pts.size()];
        const Vec2<Scalar> q = pts[(k + 1) % pts.size()];
        const Vec2<Scalar> o = pts[(k + pts.size() - 1) % pts.size()];
        const Vec2<Scalar> dir = q - o;
        double yaw = std::atan2(static_cast<double>(dir.y()), static_cast<double>(dir.x()));
        if (k > 0) {  // unwrap
          while (yaw - yawPrev > kPi) yaw -= 2 * kPi;
          while (yaw - yawPrev < -kPi) yaw += 2 * kPi;
        }
        yawPrev = yaw;
        if (t > glanceUntil && rng.chance(0.25)) {  // glance aside for a while
          glance = deg(rng.uniform(20, 45));
          if (rng.chance(0.5)) glance = -glance;
          glanceUntil = t + rng.uniform(1.0, 2.0);
        } else if (t > glanceUntil) {
          glance = 0;
        }
        CameraKey<Scalar> key;
        key.t = t;
        key.eye = V3(p.x(), p.y(), S(eyeHeight));
        key.yaw = S(yaw + glance);
        double pitch = pitchBase + deg(rng.uniform(-6, 6));
        if (glance != 0) pitch += deg(rng.uniform(-8, 8));
        key.pitch = S(pitch);
        key.roll = S(deg(rng.uniform(-2, 2)));
        path.keys.push_back(key);
        t += static_cast<double>((q - p).norm()) / speed;
      }
      path.bobAmplitude = S(rng.uniform(0.012, 0.02));
      path.stepFrequency = S(speed * 1.75);
      path.neckOffset = S(0.08);
      addJitter(path, rng, duration, 0.004, deg(1.0));
      break;
    }
    case CameraMotion::TableWork: {
      // Stand at the south (facing +y) or north (facing −y) side of the table.
      const bool south = rng.chance(0.5);
      const double cx = 0.5 * static_cast<double>(layout.tableMin.x() + layout.tableMax.x());
      const double yEdge = static_cast<double>(south ? layout.tableMin.y() : layout.tableMax.y());
      const double facing = south ? kPi / 2 : -kPi / 2;
      const double sgn = south ? 1.0 : -1.0;
      double baseX = cx + rng.uniform(-0.35, 0.35);
      double t = 0;
      while (t <= duration + 2.0) {
        CameraKey<Scalar> key;
        key.t = t;
        if (rng.chance(0.08)) baseX = std::min(cx + 0.5, std::max(cx - 0.5, baseX + rng.uniform(-0.3, 0.3)));  // step
        const double back = rng.uniform(0.32, 0.45);
        const double ex = baseX + rng.uniform(-0.05, 0.05);
        const double ez = eyeHeight + rng.uniform(-0.03, 0.02);
        key.eye = V3(S(ex), S(yEdge - sgn * back), S(ez));
        if (rng.chance(0.12)) {  // glance up into the room
          key.yaw = S(facing + deg(rng.uniform(-60, 60)));
          key.pitch = S(deg(rng.uniform(-20, -5)));
        } else {
          key.yaw = S(facing + deg(rng.uniform(-25, 25)));
          key.pitch = S(deg(rng.uniform(-65, -40)));
        }
        key.roll = S(deg(rng.uniform(-4, 4)));
        path.keys.push_back(key);
        t += rng.uniform(1.0, 2.2);
      }
      path.neckOffset = S(0.08);
      addJitter(path, rng, duration, 0.006, deg(1.2));
      break;
    }
    case CameraMotion::FastTurns: {
      const Vec2<Scalar> spot = layout.standSpots[static_cast<std::size_t>(rng.index(static_cast<int>(layout.standSpots.size())))];
      const V3 eye(spot.x(), spot.y(), S(eyeHeight));
      double yaw = rng.uniform(-kPi, kPi), pitch = deg(rng.uniform(-25, 0));
      double t = 0;
      while (t <= duration + 2.0) {
        // Fixation: a stop key, a slow drift, a stop key.
        const double dwell = rng.uniform(0.6, 1.4);
        for (int k = 0; k < 2; ++k) {
          CameraKey<Scalar> key;
          key.t = t;
          key.eye = eye;
          key.yaw = S(yaw);
          key.pitch = S(pitch);
          key.roll = S(deg(rng.uniform(-2, 2)));
          key.stop = true;
          path.keys.push_back(key);
          if (k == 0) {
            t += dwell;
            yaw += deg(rng.uniform(-5, 5));
            pitch += deg(rng.uniform(-3, 3));
          }
        }
        // Fast turn.
        double turn = deg(rng.uniform(60, 150));
        if (rng.chance(0.5)) turn = -turn;
        t += rng.uniform(0.4, 0.7);
        yaw += turn;
        pitch = deg(rng.uniform(-40, 5));
      }
      path.neckOffset = S(0.09);
      addJitter(path, rng, duration, 0.002, deg(0.6));
      break;
    }
    case CameraMotion::PureRotation: {
      const Vec2<Scalar> spot = layout.standSpots[static_cast<std::size_t>(rng.index(static_cast<int>(layout.standSpots.size())))];
      const V3 eye(spot.x(), spot.y(), S(eyeHeight));
      double yaw = rng.uniform(-kPi, kPi);
      double t = 0;
      while (t <= duration + 2.0) {
        CameraKey<Scalar> key;
        key.t = t;
        key.eye = eye;
        key.yaw = S(yaw);
        key.pitch = S(deg(rng.uniform(-45, 10)));
        key.roll = S(deg(rng.uniform(-5, 5)));
        path.keys.push_back(key);
        const double step = deg(rng.uniform(20, 70));
        yaw += rng.chance(0.5) ? step : -step;
        t += rng.uniform(0.8, 2.0);
      }
      path.neckOffset = S(0);
      addJitter(path, rng, duration, 0.0008, deg(0.8));
      break;
    }
  }
  return path;
}

}  // namespace synth
}  // namespace hawor
