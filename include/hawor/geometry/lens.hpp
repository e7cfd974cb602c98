// hawor/geometry/lens.hpp — lens distortion models: pinhole, radial-tangential (OpenCV's
// k1, k2, p1, p2, k3) and equidistant fisheye (Kannala–Brandt k1..k4, OpenCV's `fisheye`), each
// with project, unproject and Jacobians (docs/design.md §11).
//
// A lens maps a camera-frame point p (OpenCV frame: x right, y down, z forward) to distorted
// normalised coordinates m; the intrinsics make the pixel (fx·m.x + cx, fy·m.y + cy)
// (camera_model.hpp puts the two together).
//   Pinhole:  m = (x, y) with x = p.x/p.z, y = p.y/p.z
//   RadTan:   r² = x² + y²,  a = 1 + k1 r² + k2 r⁴ + k3 r⁶,
//             m = (x·a + 2 p1 x y + p2 (r² + 2x²),  y·a + p1 (r² + 2y²) + 2 p2 x y)
//   Fisheye:  r = |(p.x, p.y)|,  θ = atan2(r, p.z),  θd = θ(1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸),
//             m = (θd / r)·(p.x, p.y)   (a Taylor branch gives the r → 0 limit (x/z, y/z)); defined
//             for any direction, z ≤ 0 included, up to the model's valid angle.
// These are OpenCV's projectPoints and fisheye::projectPoints with rvec = tvec = 0.
//
// Unprojection inverts the map by Newton's method and is defined only where the map does not
// fold: up to maxMonotonicAngle(), the first angle at which the radial function stops
// increasing (fisheye: Newton on θd(θ) from θ = θd, falling back to a bracketed solve on
// [0, fold]; radial-tangential: damped 2D Newton from m, then from 0 inside the fold radius).
// Calibrated polynomials are only meaningful inside the calibrated field of view, and many fold
// just outside it; validate() checks that the field an image needs lies before the fold.
//
// A plain aggregate (Lens<double>{LensKind::Fisheye, {k1, k2, k3, k4, 0}}); thread-safe to read;
// nothing allocates except toString/parse.
#pragma once

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <type_traits>

#include "hawor/common.hpp"

namespace hawor {

enum class LensKind { Pinhole, RadTan, Fisheye };

namespace detail {

/// p(x) = c[0] + c[1]·x + … + c[n]·x^n (Horner).
template <typename Scalar>
Scalar lensPolyEval(const Scalar* c, int n, Scalar x) {
  Scalar v = c[n];
  for (int i = n - 1; i >= 0; --i) v = v * x + c[i];
  return v;
}

/// Largest degree the root finder handles (RadTan's worst-direction slope is degree 6).
constexpr int kLensMaxDegree = 8;

/// The sign changes of p (degree n ≤ 8) inside the open interval (lo, hi), sorted, written to
/// `roots`; returns how many. Exact up to rounding: p is monotonic between consecutive roots of
/// p′ (found recursively), so each monotonic piece holds at most one sign change, found by
/// Newton's method kept inside the piece. Roots where p only touches zero (even multiplicity)
/// are reported only when p is exactly 0 at a critical point; they are not sign changes.
template <typename Scalar>
int lensPolyRoots(const Scalar* c_in, int n, Scalar lo, Scalar hi, Scalar* roots) {
  while (n > 0 && c_in[n] == Scalar(0)) --n;
  if (n <= 0 || !(lo < hi)) return 0;
  if (n == 1) {
    const Scalar x = -c_in[0] / c_in[1];
    if (x > lo && x < hi) {
      roots[0] = x;
      return 1;
    }
    return 0;
  }
  Scalar d[kLensMaxDegree];
  for (int i = 1; i <= n; ++i) d[i - 1] = Scalar(i) * c_in[i];
  Scalar crit[kLensMaxDegree];
  const int m = lensPolyRoots(d, n - 1, lo, hi, crit);
  int count = 0;
  Scalar a = lo, fa = lensPolyEval(c_in, n, lo);
  for (int j = 0; j <= m; ++j) {
    const Scalar b = j < m ? crit[j] : hi;
    const Scalar fb = lensPolyEval(c_in, n, b);
    if (j < m && fb == Scalar(0)) {
      roots[count++] = b;  // touches or crosses exactly at a critical point
    } else if ((fa < Scalar(0) && fb > Scalar(0)) || (fa > Scalar(0) && fb < Scalar(0))) {
      // Newton's method kept inside the bracket [x0, x1] (p′ has one sign there), bisection
      // when a step would leave it.
      Scalar x0 = a, x1 = b, x = Scalar(0.5) * (a + b);
      const bool rising = fa < Scalar(0);
      const Scalar eps = std::numeric_limits<Scalar>::epsilon();
      for (int it = 0; it < 200; ++it) {
        const Scalar fx = lensPolyEval(c_in, n, x);
        if (fx == Scalar(0)) break;
        ((fx < Scalar(0)) == rising ? x0 : x1) = x;
        const Scalar step = fx / lensPolyEval(d, n - 1, x);
        if (std::abs(step) <= Scalar(2) * eps * std::abs(x)) {
          x -= step;  // converged
          break;
        }
        x = x - step;
        if (!(x > x0 && x < x1)) x = Scalar(0.5) * (x0 + x1);
        if (!(x > x0 && x < x1)) break;  // the bracket is down to adjacent numbers
      }
      roots[count++] = x;
    }
    a = b;
    fa = fb;
  }
  return count;
}

/// Cheap proof that p(x) > 0 on [0, hi] (hi ≥ 0): on each of `pieces` equal parts [a, b],
/// p(x) ≥ Σ_{c_i > 0} c_i a^i + Σ_{c_i < 0} c_i b^i (each term is monotonic for x ≥ 0). False
/// means "not proved" (p may still be positive).
template <typename Scalar>
bool lensPolyBoundPositive(const Scalar* c, int n, Scalar hi, int pieces) {
  for (int j = 0; j < pieces; ++j) {
    const Scalar a = hi * Scalar(j) / Scalar(pieces), b = hi * Scalar(j + 1) / Scalar(pieces);
    Scalar bound = c[0], ap = Scalar(1), bp = Scalar(1);
    for (int i = 1; i <= n; ++i) {
      ap *= a;
      bp *= b;
      bound += c[i] * (c[i] > Scalar(0) ? ap : bp);
    }
    if (!(bound > Scalar(0))) return false;
  }
  return true;
}

/// The smallest x in (lo, hi] with p(x) ≤ 0, for p(lo) > 0; +∞ when p stays positive.
template <typename Scalar>
Scalar lensFirstNonPositive(const Scalar* c, int n, Scalar lo, Scalar hi) {
  Scalar r[kLensMaxDegree];
  const int m = lensPolyRoots(c, n, lo, hi, r);
  if (m > 0) return r[0];
  return lensPolyEval(c, n, hi) <= Scalar(0) ? hi : std::numeric_limits<Scalar>::infinity();
}

/// Parses a whole string as a number of type Scalar (strtof for float, so that the shortest
/// decimal of a float reads back to the same float); false unless every character is used.
template <typename Scalar>
bool lensParseNumber(const std::string& s, Scalar& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  if (std::is_same<Scalar, float>::value) {
    out = static_cast<Scalar>(std::strtof(s.c_str(), &end));
  } else {
    out = static_cast<Scalar>(std::strtod(s.c_str(), &end));
  }
  return end == s.c_str() + s.size();
}

/// The shortest "%g" decimal that parses back to exactly v (at most max_digits10 digits).
template <typename Scalar>
std::string lensShortest(Scalar v) {
  char buf[64];
  for (int prec = 1; prec <= std::numeric_limits<Scalar>::max_digits10; ++prec) {
    std::snprintf(buf, sizeof(buf), "%.*g", prec, static_cast<double>(v));
    Scalar back = Scalar(0);
    if (lensParseNumber<Scalar>(buf, back) && back == v) break;
  }
  return buf;
}

inline std::string lensTrim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

}  // namespace detail

template <typename Scalar>
struct Lens {
  LensKind kind = LensKind::Pinhole;
  /// RadTan: k1, k2, p1, p2, k3 (OpenCV's order); Fisheye: k1..k4 and k[4] = 0; Pinhole: zeros.
  std::array<Scalar, 5> k{};

  static Lens pinhole() { return Lens(); }
  static Lens radTan(Scalar k1, Scalar k2, Scalar p1, Scalar p2, Scalar k3 = Scalar(0)) {
    Lens l;
    l.kind = LensKind::RadTan;
    l.k = {k1, k2, p1, p2, k3};
    return l;
  }
  static Lens fisheye(Scalar k1, Scalar k2, Scalar k3, Scalar k4) {
    Lens l;
    l.kind = LensKind::Fisheye;
    l.k = {k1, k2, k3, k4, Scalar(0)};
    return l;
  }

  /// True when the lens does not distort: Pinhole, or RadTan with every coefficient 0
  /// (a fisheye with k = 0 is the equidistant model θd = θ, not a pinhole).
  bool isPinhole() const {
    return kind == LensKind::Pinhole || (kind == LensKind::RadTan && allZero());
  }

  /// Camera-frame point p → distorted normalised coordinates m (formulas in the file comment).
  /// Pinhole/RadTan are meaningful for z > 0 only (z = 0 gives inf, z < 0 the mirrored point,
  /// as PinholeCamera::project); Fisheye for any p ≠ 0 off the backward axis. J (optional)
  /// receives dm/dp (2×3); nothing is computed for it when null.
  Vec2<Scalar> project(const Vec3<Scalar>& p, Eigen::Matrix<Scalar, 2, 3>* J = nullptr) const {
    if (kind == LensKind::Fisheye) return projectFisheye(p, J);
    const Scalar iz = Scalar(1) / p(2);
    const Vec2<Scalar> xy(p(0) * iz, p(1) * iz);
    if (kind == LensKind::Pinhole) {
      if (J) {
        *J << iz, Scalar(0), -xy(0) * iz,  //
            Scalar(0), iz, -xy(1) * iz;
      }
      return xy;
    }
    if (!J) return distortRadTan(xy, nullptr);
    // dm/dp = dm/dxy · dxy/dp,  dxy/dp = [1/z, 0, −x/z; 0, 1/z, −y/z].
    Eigen::Matrix<Scalar, 2, 2> Jd;
    const Vec2<Scalar> m = distortRadTan(xy, &Jd);
    J->template leftCols<2>() = Jd * iz;
    J->col(2) = -(Jd * xy) * iz;
    return m;
  }

  /// Distorted normalised m → unit bearing vector. False (bearing untouched) for a non-finite
  /// m, an m outside what the model reaches before it folds (see maxMonotonicAngle), or no
  /// convergence. Pinhole/RadTan bearings have z > 0; a fisheye's may point backwards.
  bool unproject(const Vec2<Scalar>& m, Vec3<Scalar>& bearing) const {
    if (!allFinite(m)) return false;
    if (kind == LensKind::Fisheye) {
      const Scalar td = m.norm();
      Scalar theta;
      if (!solveFisheyeTheta(td, theta)) return false;
      if (td == Scalar(0)) {
        bearing = Vec3<Scalar>(Scalar(0), Scalar(0), Scalar(1));
        return true;
      }
      using std::cos;
      using std::sin;
      const Scalar s = sin(theta) / td;
      bearing = Vec3<Scalar>(s * m(0), s * m(1), cos(theta));
      return true;
    }
    Vec2<Scalar> xy;
    if (!undistort(m, xy)) return false;
    bearing = Vec3<Scalar>(xy(0), xy(1), Scalar(1)).normalized();
    return true;
  }

  /// Distorted normalised m → undistorted normalised (x, y) on the plane z = 1 (the pinhole
  /// coordinates of the same ray). False (xy untouched) where unproject fails, and for fisheye
  /// rays at 90° or more from the axis (no z = 1 point).
  bool undistort(const Vec2<Scalar>& m, Vec2<Scalar>& xy) const {
    if (!allFinite(m)) return false;
    if (kind == LensKind::Pinhole) {
      xy = m;
      return true;
    }
    if (kind == LensKind::Fisheye) {
      const Scalar td = m.norm();
      Scalar theta;
      if (!solveFisheyeTheta(td, theta)) return false;
      if (!(theta < Constants<Scalar>::pi() / Scalar(2))) return false;
      using std::tan;
      // (x, y) = tan θ · m/|m|; θ/θd → 1 as θd → 0.
      xy = td == Scalar(0) ? m : Vec2<Scalar>(m * (tan(theta) / td));
      return true;
    }
    return undistortRadTan(m, xy);
  }

  /// The z = 1 form of project: undistorted normalised (x, y) → distorted m, J = dm/d(x, y).
  /// Fisheye: θ = atan(r), m = (θd/r)·(x, y).
  Vec2<Scalar> distort(const Vec2<Scalar>& xy, Eigen::Matrix<Scalar, 2, 2>* J = nullptr) const {
    if (kind == LensKind::RadTan) return distortRadTan(xy, J);
    if (kind == LensKind::Pinhole) {
      if (J) J->setIdentity();
      return xy;
    }
    if (!J) return projectFisheye(Vec3<Scalar>(xy(0), xy(1), Scalar(1)), nullptr);
    Eigen::Matrix<Scalar, 2, 3> J3;
    const Vec2<Scalar> m = projectFisheye(Vec3<Scalar>(xy(0), xy(1), Scalar(1)), &J3);
    *J = J3.template leftCols<2>();
    return m;
  }

  /// Largest field angle (radians from the optical axis) up to which project is invertible,
  /// i.e. the radial map strictly increases:
  ///   Fisheye: the first root of dθd/dθ = 1 + 3k1 θ² + 5k2 θ⁴ + 7k3 θ⁶ + 9k4 θ⁸, capped at π.
  ///   RadTan:  along a ray of direction d = (cos φ, sin φ) the distorted point's component
  ///            along d is r·a(r²) + 3 r² (p1 sin φ + p2 cos φ); its slope at the worst φ,
  ///            1 − 6 r √(p1² + p2²) + 3k1 r² + 5k2 r⁴ + 7k3 r⁶, is searched for its first root
  ///            up to r = 1000 (89.94°); atan of that radius, π/2 when it stays positive.
  ///            (Without p1, p2 this is exactly dr_d/dr.)
  ///   Pinhole: π/2.
  /// Exact up to rounding (polynomial roots isolated between critical points); NaN for
  /// non-finite coefficients.
  Scalar maxMonotonicAngle() const {
    using std::atan;
    using std::sqrt;
    const Scalar pi = Constants<Scalar>::pi();
    if (!coefficientsFinite()) return std::numeric_limits<Scalar>::quiet_NaN();
    if (kind == LensKind::Pinhole) return pi / Scalar(2);
    if (kind == LensKind::Fisheye) {
      const Scalar c[5] = {Scalar(1), 3 * k[0], 5 * k[1], 7 * k[2], 9 * k[3]};
      const Scalar u = detail::lensFirstNonPositive(c, 4, Scalar(0), pi * pi);
      return u <= pi * pi ? sqrt(u) : pi;
    }
    const Scalar r = radTanFoldRadius(Scalar(1000));
    return std::isfinite(r) ? atan(r) : pi / Scalar(2);
  }

  /// True when the radial map strictly increases from the axis out to `angle` (radians), i.e.
  /// angle ≤ maxMonotonicAngle() (angle < π/2 for Pinhole/RadTan, ≤ π for Fisheye). A cheap
  /// bound (every negative term of the slope at its largest) decides most calls; the exact
  /// root search runs only when the bound is inconclusive.
  bool monotonicUpTo(Scalar angle) const {
    using std::tan;
    const Scalar pi = Constants<Scalar>::pi();
    if (!(angle >= Scalar(0)) || !coefficientsFinite()) return false;
    if (kind == LensKind::Fisheye) {
      if (angle > pi) return false;
      return fisheyeMonotonicUpTo(angle);
    }
    if (!(angle < pi / Scalar(2))) return false;
    if (kind == LensKind::Pinhole) return true;
    return radTanMonotonicUpToRadius(tan(angle));
  }

  /// True when the camera-frame point p lies in the model's domain: finite, and within the
  /// angle where project is invertible (z > 0 for Pinhole/RadTan; monotonicUpTo its angle).
  bool inDomain(const Vec3<Scalar>& p) const {
    using std::atan2;
    using std::sqrt;
    if (!allFinite(p)) return false;
    const Scalar r = sqrt(p(0) * p(0) + p(1) * p(1));
    if (kind == LensKind::Fisheye) {
      if (r == Scalar(0) && !(p(2) > Scalar(0))) return false;  // the origin, the back axis
      return fisheyeMonotonicUpTo(atan2(r, p(2)));
    }
    if (!(p(2) > Scalar(0))) return false;
    if (kind == LensKind::Pinhole) return true;
    return radTanMonotonicUpToRadius(r / p(2));
  }

  /// Throws hawor::Error naming the problem when the lens cannot serve a field of `maxAngle`
  /// radians from the axis: non-finite coefficients; coefficients the model does not use set
  /// (pinhole with any, fisheye with k[4]); an angle a pinhole-type model cannot see (≥ 90°) or
  /// beyond π; a model that folds before maxAngle (the fold angle is named).
  void validate(Scalar maxAngle) const {
    static const char* const radtan_names[5] = {"k1", "k2", "p1", "p2", "k3"};
    static const char* const fisheye_names[5] = {"k1", "k2", "k3", "k4", "k[4]"};
    const char* const* names = kind == LensKind::RadTan ? radtan_names : fisheye_names;
    for (std::size_t i = 0; i < 5; ++i) {
      if (!std::isfinite(k[i])) {
        throw Error("lens " + toString() + ": coefficient " + names[i] + " is not finite (" +
                    detail::lensShortest(k[i]) + ")");
      }
    }
    if (kind == LensKind::Pinhole && !allZero()) {
      throw Error("lens: a pinhole lens has no coefficients, but k holds " + coefficientList(5) +
                  " (use LensKind::RadTan or Fisheye)");
    }
    if (kind == LensKind::Fisheye && k[4] != Scalar(0)) {
      throw Error("lens " + toString() + ": the fisheye model uses k1..k4; k[4] must be 0, got " +
                  detail::lensShortest(k[4]));
    }
    if (!std::isfinite(maxAngle) || maxAngle < Scalar(0)) {
      throw Error("lens " + toString() + ": the field angle to cover is not a finite angle >= 0 (" +
                  detail::lensShortest(maxAngle) + ")");
    }
    const Scalar pi = Constants<Scalar>::pi();
    if (kind != LensKind::Fisheye && !(maxAngle < pi / Scalar(2))) {
      throw Error("lens " + toString() + ": a " +
                  (kind == LensKind::Pinhole ? std::string("pinhole") : "radial-tangential") +
                  " model sees less than 90 degrees from the axis, but " + degrees(maxAngle) +
                  " are needed (use a fisheye model)");
    }
    if (kind == LensKind::Fisheye && maxAngle > pi) {
      throw Error("lens " + toString() + ": no direction is more than 180 degrees from the axis (" +
                  degrees(maxAngle) + " asked)");
    }
    if (!monotonicUpTo(maxAngle)) {
      const Scalar fold = maxMonotonicAngle();
      throw Error("lens " + toString() + ": the model folds at " + degrees(fold) +
                  " from the optical axis (" +
                  (kind == LensKind::Fisheye ? std::string("theta_d(theta)") : "r_d(r)") +
                  " stops increasing there), before the " + degrees(maxAngle) +
                  " the image needs: the coefficients do not describe a lens out to the image "
                  "corners (a calibration fitted on a smaller field, or a typo)");
    }
  }

  /// "pinhole" | "opencv:k1,k2,p1,p2,k3" | "fisheye:k1,k2,k3,k4", each number the shortest
  /// decimal that reads back to the same Scalar (parse(toString()) reproduces the lens).
  std::string toString() const {
    if (kind == LensKind::Pinhole) return "pinhole";
    return (kind == LensKind::RadTan ? "opencv:" : "fisheye:") +
           coefficientList(kind == LensKind::RadTan ? 5 : 4);
  }

  /// Reads "pinhole", "opencv:k1,k2,p1,p2[,k3]" or "fisheye:k1,k2,k3,k4" (model names in any
  /// case, spaces around tokens allowed). Throws hawor::Error quoting the text and saying what
  /// is wrong: unknown model, wrong number of coefficients, a coefficient that is not a number
  /// or not finite.
  static Lens parse(const std::string& text) {
    const char* expected = "expected pinhole, opencv:k1,k2,p1,p2[,k3] or fisheye:k1,k2,k3,k4";
    const std::string t = detail::lensTrim(text);
    if (t.empty()) parseError(text, std::string("empty lens description (") + expected + ")");
    const std::size_t colon = t.find(':');
    std::string name = detail::lensTrim(t.substr(0, colon));
    for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (name == "pinhole") {
      if (colon != std::string::npos) parseError(text, "the pinhole model takes no coefficients");
      return pinhole();
    }
    const bool radtan = name == "opencv";
    if (!radtan && name != "fisheye") {
      parseError(text, "unknown lens model \"" + name + "\" (" + expected + ")");
    }
    const char* form = radtan ? "opencv:k1,k2,p1,p2[,k3]" : "fisheye:k1,k2,k3,k4";
    if (colon == std::string::npos)
      parseError(text, std::string("missing coefficients (") + form + ")");
    static const char* const radtan_names[5] = {"k1", "k2", "p1", "p2", "k3"};
    static const char* const fisheye_names[4] = {"k1", "k2", "k3", "k4"};
    const std::string rest = t.substr(colon + 1);
    if (detail::lensTrim(rest).empty()) {
      parseError(text, std::string("missing coefficients after ':' (") + form + ")");
    }
    std::string tokens[6];
    int count = 0;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = rest.find(',', start);
      if (count < 6) tokens[count] = detail::lensTrim(rest.substr(start, comma - start));
      ++count;
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    const bool countOk = radtan ? (count == 4 || count == 5) : count == 4;
    if (!countOk) {
      parseError(text, std::string(radtan ? "the opencv model takes 4 or 5 coefficients"
                                          : "the fisheye model takes 4 coefficients") +
                           " (" + form + "), got " + std::to_string(count));
    }
    Lens l;
    l.kind = radtan ? LensKind::RadTan : LensKind::Fisheye;
    for (int i = 0; i < count; ++i) {
      const std::string what = "coefficient " + std::to_string(i + 1) + " (" +
                               (radtan ? radtan_names[i] : fisheye_names[i]) + ")";
      Scalar v = Scalar(0);
      if (tokens[i].empty()) parseError(text, what + " is empty");
      if (!detail::lensParseNumber(tokens[i], v)) {
        parseError(text, what + " \"" + tokens[i] + "\" is not a number");
      }
      if (!std::isfinite(v)) parseError(text, what + " is not finite (" + tokens[i] + ")");
      l.k[static_cast<std::size_t>(i)] = v;
    }
    return l;
  }

  template <typename T>
  Lens<T> cast() const {
    Lens<T> l;
    l.kind = kind;
    for (std::size_t i = 0; i < 5; ++i) l.k[i] = static_cast<T>(k[i]);
    return l;
  }

 private:
  [[noreturn]] static void parseError(const std::string& text, const std::string& why) {
    throw Error("lens \"" + text + "\": " + why);
  }

  bool allZero() const {
    for (Scalar c : k)
      if (c != Scalar(0)) return false;
    return true;
  }
  bool coefficientsFinite() const {
    for (Scalar c : k)
      if (!std::isfinite(c)) return false;
    return true;
  }

  std::string coefficientList(int n) const {
    std::string s;
    for (int i = 0; i < n; ++i) {
      if (i) s += ",";
      s += detail::lensShortest(k[static_cast<std::size_t>(i)]);
    }
    return s;
  }

  static std::string degrees(Scalar a) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.1f degrees (%.4f rad)",
                  static_cast<double>(a) * 180.0 / 3.14159265358979323846, static_cast<double>(a));
    return buf;
  }

  // θd(θ) = θ(1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) and its derivative.
  Scalar thetaD(Scalar t) const {
    const Scalar t2 = t * t;
    return t * (Scalar(1) + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
  }
  Scalar thetaDPrime(Scalar t) const {
    const Scalar t2 = t * t;
    return Scalar(1) +
           t2 * (Scalar(3) * k[0] +
                 t2 * (Scalar(5) * k[1] + t2 * (Scalar(7) * k[2] + t2 * Scalar(9) * k[3])));
  }

  // Fisheye projection. With s = θd/r:  m = s·(x, y),
  //   dm/d(x, y) = s·I + g·(x, y)(x, y)ᵀ,  g = (θd′·z/ρ² − s)/r²,  dm/dz = −θd′/ρ²·(x, y)
  // (ρ² = r² + z²). For θ² < ε (θ < 1e-5 in double) the Taylor forms
  //   s = (θd/θ)(1 + θ²/6)/ρ,  g = ((2k1 − 2/3) + (4k2 − k1 − 1/5) θ²)/ρ³
  // replace the quotients by r (exact at r = 0, where m = (x/z, y/z)).
  Vec2<Scalar> projectFisheye(const Vec3<Scalar>& p, Eigen::Matrix<Scalar, 2, 3>* J) const {
    using std::atan2;
    using std::sqrt;
    const Scalar x = p(0), y = p(1), z = p(2);
    const Scalar r2 = x * x + y * y, r = sqrt(r2);
    const Scalar theta = atan2(r, z), t2 = theta * theta;
    const Scalar poly = Scalar(1) + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
    const bool small = t2 < Constants<Scalar>::epsilon();
    Scalar rho2 = Scalar(0), rho = Scalar(0), s;
    if (small) {
      rho2 = r2 + z * z;
      rho = sqrt(rho2);
      s = poly * (Scalar(1) + t2 / Scalar(6)) / rho;
    } else {
      s = theta * poly / r;
    }
    if (J) {
      if (!small) rho2 = r2 + z * z;
      const Scalar dpoly = thetaDPrime(theta);
      Scalar g;
      if (small) {
        g = ((Scalar(2) * k[0] - Scalar(2) / Scalar(3)) +
             (Scalar(4) * k[1] - k[0] - Scalar(0.2)) * t2) /
            (rho2 * rho);
      } else {
        g = (dpoly * z / rho2 - s) / r2;
      }
      const Scalar dz = -dpoly / rho2;
      *J << s + g * x * x, g * x * y, dz * x,  //
          g * x * y, s + g * y * y, dz * y;
    }
    return Vec2<Scalar>(s * x, s * y);
  }

  // RadTan on the z = 1 plane, with dm/d(x, y) =
  //   [a + 2x²·a′ + 2p1 y + 6p2 x,   2xy·a′ + 2p1 x + 2p2 y]
  //   [2xy·a′ + 2p1 x + 2p2 y,       a + 2y²·a′ + 6p1 y + 2p2 x],  a′ = k1 + 2k2 r² + 3k3 r⁴.
  Vec2<Scalar> distortRadTan(const Vec2<Scalar>& xy, Eigen::Matrix<Scalar, 2, 2>* J) const {
    const Scalar x = xy(0), y = xy(1);
    const Scalar k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3], k3 = k[4];
    const Scalar r2 = x * x + y * y;
    const Scalar a = Scalar(1) + r2 * (k1 + r2 * (k2 + r2 * k3));
    const Scalar xy2 = Scalar(2) * x * y;
    const Vec2<Scalar> m(x * a + p1 * xy2 + p2 * (r2 + Scalar(2) * x * x),
                         y * a + p1 * (r2 + Scalar(2) * y * y) + p2 * xy2);
    if (J) {
      const Scalar da = k1 + r2 * (Scalar(2) * k2 + Scalar(3) * k3 * r2);
      const Scalar off = xy2 * da + Scalar(2) * (p1 * x + p2 * y);
      *J << a + Scalar(2) * x * x * da + Scalar(2) * p1 * y + Scalar(6) * p2 * x, off,  //
          off, a + Scalar(2) * y * y * da + Scalar(6) * p1 * y + Scalar(2) * p2 * x;
    }
    return m;
  }

  // Slope of RadTan's radial map along the worst direction (see maxMonotonicAngle), as a
  // polynomial in r: 1 − 6|p| r + 3k1 r² + 5k2 r⁴ + 7k3 r⁶.
  void radTanSlope(Scalar c[7]) const {
    using std::sqrt;
    c[0] = Scalar(1);
    c[1] = Scalar(-6) * sqrt(k[2] * k[2] + k[3] * k[3]);
    c[2] = Scalar(3) * k[0];
    c[3] = Scalar(0);
    c[4] = Scalar(5) * k[1];
    c[5] = Scalar(0);
    c[6] = Scalar(7) * k[4];
  }
  // First radius in (0, hi] where that slope is ≤ 0; +∞ when none.
  Scalar radTanFoldRadius(Scalar hi) const {
    Scalar c[7];
    radTanSlope(c);
    return detail::lensFirstNonPositive(c, 6, Scalar(0), hi);
  }
  // Monotonic out to radius r / angle θ: the cheap bound on the whole range, then on 4 and 16
  // pieces (each a proof), and only then the exact first root.
  bool radTanMonotonicUpToRadius(Scalar r) const {
    if (!(r >= Scalar(0)) || !std::isfinite(r)) return false;
    Scalar c[7];
    radTanSlope(c);
    for (int pieces : {1, 4, 16})
      if (detail::lensPolyBoundPositive(c, 6, r, pieces)) return true;
    return !(detail::lensFirstNonPositive(c, 6, Scalar(0), r) <= r);
  }
  // The bounds alone for the fisheye's slope θd′ (a polynomial in u = θ²) on [0, θ].
  bool fisheyeBoundPositive(Scalar theta) const {
    const Scalar c[5] = {Scalar(1), 3 * k[0], 5 * k[1], 7 * k[2], 9 * k[3]};
    const Scalar u = theta * theta;
    for (int pieces : {1, 4, 16})
      if (detail::lensPolyBoundPositive(c, 4, u, pieces)) return true;
    return false;
  }
  bool fisheyeMonotonicUpTo(Scalar theta) const {
    if (!(theta >= Scalar(0)) || !(theta <= Constants<Scalar>::pi())) return false;
    if (fisheyeBoundPositive(theta)) return true;
    const Scalar c[5] = {Scalar(1), 3 * k[0], 5 * k[1], 7 * k[2], 9 * k[3]};
    const Scalar u = theta * theta;
    return !(detail::lensFirstNonPositive(c, 4, Scalar(0), u) <= u);
  }

  // θ in [0, hi] with θd(θ) = td, for θd increasing on the bracket: Newton's method, falling
  // back to bisection whenever a step would leave the bracket.
  bool solveThetaIn(Scalar td, Scalar hi, Scalar& theta) const {
    using std::abs;
    const Scalar eps = std::numeric_limits<Scalar>::epsilon();
    Scalar lo = Scalar(0), t = std::min(td, hi);
    for (int it = 0; it < 200; ++it) {
      const Scalar f = thetaD(t) - td;
      if (f == Scalar(0)) break;
      (f < Scalar(0) ? lo : hi) = t;
      const Scalar d = thetaDPrime(t), step = f / d;
      if (d > Scalar(0) && abs(step) <= Scalar(2) * eps * t) {
        t -= step;  // converged (tested before the bracket: a sub-ulp step may land on lo/hi)
        break;
      }
      Scalar next = t - step;
      if (!(d > Scalar(0)) || !(next > lo && next < hi)) next = Scalar(0.5) * (lo + hi);
      t = next;
      if (hi - lo <= Scalar(2) * eps * hi) break;
    }
    if (!std::isfinite(t)) return false;
    theta = t;
    return abs(thetaD(t) - td) <= Scalar(64) * eps * std::max(td, Scalar(1e-30));
  }

  // The fisheye's θ for distorted radius td on the monotonic branch; false beyond it.
  bool solveFisheyeTheta(Scalar td, Scalar& theta) const {
    if (!std::isfinite(td) || td < Scalar(0) || !coefficientsFinite()) return false;
    if (td == Scalar(0)) {
      theta = Scalar(0);
      return true;
    }
    using std::abs;
    const Scalar pi = Constants<Scalar>::pi(), eps = std::numeric_limits<Scalar>::epsilon();
    // Usual case: plain Newton from θ = θd converges to a root θ*, and the cheap bound shows
    // θd increasing on [0, θ*]: then θ* is the only root there, on the monotonic branch.
    Scalar t = std::min(td, pi);
    for (int it = 0; it < 30; ++it) {
      const Scalar d = thetaDPrime(t);
      if (!(d > Scalar(0))) break;
      const Scalar step = (thetaD(t) - td) / d;
      t -= step;
      if (!(t > Scalar(0) && t <= pi)) break;
      if (abs(step) <= Scalar(2) * eps * t) {
        if (abs(thetaD(t) - td) <= Scalar(64) * eps * td && fisheyeBoundPositive(t)) {
          theta = t;
          return true;
        }
        break;
      }
    }
    // Otherwise: bracketed Newton on the monotonic part only.
    const Scalar tmax = maxMonotonicAngle();
    if (!(thetaD(tmax) >= td)) return false;
    return solveThetaIn(td, tmax, theta);
  }

  // Newton on the 2D map (x, y) ↦ distort(x, y) = m, with step halving when a step does not
  // reduce the residual or reaches a point where the map folds (det J ≤ 0). It starts from
  // (x, y) = m; when that fails, again from (0, 0) with every iterate kept inside the fold
  // radius: a strong pincushion lens maps the domain's edge beyond its own fold radius, where
  // m is no starting point and the polynomial may rise again to a second, folded solution.
  // The solution must lie where the map does not fold.
  bool undistortRadTan(const Vec2<Scalar>& m, Vec2<Scalar>& out) const {
    Vec2<Scalar> xy;
    if (!newtonRadTan(m, m, std::numeric_limits<Scalar>::infinity(), xy) &&
        !newtonRadTan(m, Vec2<Scalar>::Zero(), radTanFoldRadius(Scalar(1000)), xy)) {
      return false;
    }
    out = xy;
    return true;
  }
  bool newtonRadTan(const Vec2<Scalar>& m, const Vec2<Scalar>& start, Scalar rlimit,
                    Vec2<Scalar>& out) const {
    using std::sqrt;
    const Scalar eps = std::numeric_limits<Scalar>::epsilon();
    // Relative tolerances: the residual's rounding floor is a few ε·|m|.
    const Scalar scale = m.norm() + std::numeric_limits<Scalar>::min();
    const Scalar tight = Scalar(4) * eps * scale, loose = Scalar(64) * eps * scale;
    auto det2 = [](const Eigen::Matrix<Scalar, 2, 2>& A) {
      return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
    };
    Vec2<Scalar> xy = start;
    Eigen::Matrix<Scalar, 2, 2> J;
    Vec2<Scalar> e = distortRadTan(xy, &J) - m;
    Scalar en = e.norm();
    bool ok = false;
    int stalled = 0;  // damped steps in a row that gained < 1% (no solution nearby)
    for (int it = 0; it < 50 && stalled < 4; ++it) {
      if (en <= tight) {
        ok = true;
        break;
      }
      const Scalar det = det2(J);
      if (!(det > Scalar(0)) || !std::isfinite(det)) break;
      const Vec2<Scalar> step((J(1, 1) * e(0) - J(0, 1) * e(1)) / det,
                              (J(0, 0) * e(1) - J(1, 0) * e(0)) / det);
      if (step.norm() <= sqrt(eps) * (xy.norm() + std::numeric_limits<Scalar>::min())) {
        // Quadratic convergence: after a step this small the error is ~ε·|xy|.
        xy -= step;
        e = distortRadTan(xy, nullptr) - m;
        en = e.norm();
        break;
      }
      Scalar alpha = Scalar(1);
      bool improved = false;
      for (int ls = 0; ls < 20; ++ls, alpha *= Scalar(0.5)) {
        const Vec2<Scalar> cand = xy - alpha * step;
        Eigen::Matrix<Scalar, 2, 2> Jc;
        const Vec2<Scalar> ec = distortRadTan(cand, &Jc) - m;
        const Scalar ecn = ec.norm();
        if (ecn < en && det2(Jc) > Scalar(0) && cand.norm() < rlimit) {
          stalled = alpha < Scalar(1) && ecn > Scalar(0.99) * en ? stalled + 1 : 0;
          xy = cand;
          J = Jc;
          e = ec;
          en = ecn;
          improved = true;
          break;
        }
      }
      if (!improved) break;
    }
    if (!ok) ok = en <= loose;
    if (!ok || !allFinite(xy) || !radTanMonotonicUpToRadius(xy.norm())) return false;
    out = xy;
    return true;
  }
};

using Lensf = Lens<float>;
using Lensd = Lens<double>;

}  // namespace hawor
