// hawor/io/tum.hpp — TUM RGB-D trajectory files and timestamp association.
//
// Format (TUM RGB-D benchmark, read by evo and most SLAM tools): one pose per line,
//   timestamp tx ty tz qx qy qz qw
// separated by spaces or tabs; lines starting with '#' and blank lines are skipped. The pose is
// camera-to-world (docs/design.md §2): (tx, ty, tz) is the camera centre in the world frame and the
// quaternion, in x y z w order in the file, rotates camera axes into world axes. Inside the
// library quaternions are Eigen's (w, x, y, z).
// Reading normalises quaternions and rejects malformed lines (wrong field count, non-numbers,
// NaN/Inf, zero quaternions) and timestamps that are not strictly increasing, naming file and line.
// Numbers are written in the shortest form that reads back to the identical value.
#pragma once

#include <algorithm>
#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "../common.hpp"
#include "file.hpp"

namespace hawor {

/// One trajectory sample: time in seconds, camera-to-world rotation and camera centre.
template <typename Scalar>
struct TumPose {
  double t = 0;
  Eigen::Quaternion<Scalar, Eigen::DontAlign> q{Eigen::Quaternion<Scalar, Eigen::DontAlign>::Identity()};
  Vec3<Scalar> p{Vec3<Scalar>::Zero()};
};

namespace detail {

/// Parses a plain decimal number ([+-] digits [. digits] [e[+-]digits]); false for anything
/// else (hex, "nan", "inf", trailing text) or a value that overflows to infinity. Independent of
/// the C locale's decimal point.
inline bool parseDecimal(const std::string& tok, double* out) {
  size_t i = 0, n = tok.size();
  if (i < n && (tok[i] == '+' || tok[i] == '-')) ++i;
  size_t digits = 0;
  while (i < n && tok[i] >= '0' && tok[i] <= '9') ++i, ++digits;
  if (i < n && tok[i] == '.') {
    ++i;
    while (i < n && tok[i] >= '0' && tok[i] <= '9') ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < n && (tok[i] == 'e' || tok[i] == 'E')) {
    ++i;
    if (i < n && (tok[i] == '+' || tok[i] == '-')) ++i;
    size_t exp_digits = 0;
    while (i < n && tok[i] >= '0' && tok[i] <= '9') ++i, ++exp_digits;
    if (exp_digits == 0) return false;
  }
  if (i != n) return false;
  std::string s = tok;
  const char point = std::localeconv()->decimal_point[0];
  if (point != '.') std::replace(s.begin(), s.end(), '.', point);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

/// Shortest "%.{p}g" rendering (p from 15, or 6 for float) that parses back to exactly `v`.
inline std::string formatShortest(double v, bool single_precision) {
  char buf[48];
  const char point = std::localeconv()->decimal_point[0];
  for (int p = single_precision ? 6 : 15; p <= 17; ++p) {
    std::snprintf(buf, sizeof buf, "%.*g", p, v);
    std::string s(buf);
    if (point != '.') std::replace(s.begin(), s.end(), point, '.');
    double back = 0;
    if (!parseDecimal(s, &back)) continue;
    const bool same = single_precision ? static_cast<float>(back) == static_cast<float>(v) : back == v;
    if (same) return s;
  }
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s(buf);
  if (point != '.') std::replace(s.begin(), s.end(), point, '.');
  return s;
}

}  // namespace detail

/// Parses TUM trajectory text. `what` (the file name) and the 1-based line number prefix errors.
template <typename Scalar>
std::vector<TumPose<Scalar>> parseTum(const std::string& text, const std::string& what) {
  std::vector<TumPose<Scalar>> poses;
  std::vector<std::string> fields;
  size_t line_no = 0, prev_line = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    ++line_no;
    const std::string where = what + ":" + std::to_string(line_no);
    fields.clear();
    size_t i = pos;
    while (i < eol) {
      while (i < eol && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == '\v' ||
                         text[i] == '\f')) {
        ++i;
      }
      if (i == eol) break;
      const size_t b = i;
      while (i < eol && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' && text[i] != '\v' &&
             text[i] != '\f') {
        ++i;
      }
      fields.emplace_back(text, b, i - b);
    }
    pos = eol + 1;
    if (fields.empty() || fields[0][0] == '#') continue;
    if (fields.size() != 8) {
      throw Error(where + ": expected 8 fields 'timestamp tx ty tz qx qy qz qw', found " +
                  std::to_string(fields.size()));
    }
    double v[8];
    for (size_t k = 0; k < 8; ++k) {
      if (!detail::parseDecimal(fields[k], &v[k])) {
        std::string shown = fields[k].substr(0, 40);
        for (char& c : shown) {
          if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) >= 127) c = '?';
        }
        throw Error(where + ": field " + std::to_string(k + 1) + " ('" + shown +
                    "') is not a finite number");
      }
    }
    // |q| scaled by its largest component so that huge components cannot overflow.
    const double m = std::max(std::max(std::fabs(v[4]), std::fabs(v[5])),
                              std::max(std::fabs(v[6]), std::fabs(v[7])));
    if (!(m > 0)) throw Error(where + ": quaternion is zero");
    const double norm = m * std::sqrt((v[4] / m) * (v[4] / m) + (v[5] / m) * (v[5] / m) +
                                      (v[6] / m) * (v[6] / m) + (v[7] / m) * (v[7] / m));
    for (size_t k = 1; k < 4; ++k) {
      if (std::fabs(v[k]) > static_cast<double>(std::numeric_limits<Scalar>::max())) {
        throw Error(where + ": field " + std::to_string(k + 1) + " is out of range for " +
                    (sizeof(Scalar) == sizeof(float) ? "float" : "the scalar type"));
      }
    }
    if (!poses.empty() && !(v[0] > poses.back().t)) {
      throw Error(where + ": timestamp " + detail::formatShortest(v[0], false) +
                  " is not greater than " + detail::formatShortest(poses.back().t, false) +
                  " on line " + std::to_string(prev_line) + " (timestamps must increase)");
    }
    TumPose<Scalar> pose;
    pose.t = v[0];
    pose.p = Vec3<Scalar>(Scalar(v[1]), Scalar(v[2]), Scalar(v[3]));
    // File order x y z w; Eigen's constructor takes w x y z.
    pose.q = Eigen::Quaternion<Scalar, Eigen::DontAlign>(Scalar(v[7] / norm), Scalar(v[4] / norm),
                                                         Scalar(v[5] / norm), Scalar(v[6] / norm));
    poses.push_back(pose);
    prev_line = line_no;
  }
  return poses;
}

/// Reads a TUM trajectory file (see parseTum).
template <typename Scalar>
std::vector<TumPose<Scalar>> readTum(const std::string& path) {
  return parseTum<Scalar>(readFileText(path), path);
}

/// TUM text for `poses`: a '#' header line, then one line per pose with the unit quaternion in
/// x y z w order. Throws for non-finite values, zero quaternions or non-increasing timestamps,
/// so that whatever is written reads back.
template <typename Scalar>
std::string formatTum(const std::vector<TumPose<Scalar>>& poses) {
  const bool single = sizeof(Scalar) <= sizeof(float);
  std::string out = "# timestamp tx ty tz qx qy qz qw\n";
  for (size_t i = 0; i < poses.size(); ++i) {
    const TumPose<Scalar>& s = poses[i];
    const std::string where = "writeTum: pose " + std::to_string(i);
    if (!std::isfinite(s.t) || !s.p.allFinite() || !s.q.coeffs().allFinite()) {
      throw Error(where + " has a non-finite value");
    }
    if (i > 0 && !(s.t > poses[i - 1].t)) throw Error(where + ": timestamps must increase");
    const Scalar norm = s.q.norm();
    if (!(norm > Scalar(0))) throw Error(where + ": quaternion is zero");
    const Eigen::Quaternion<Scalar, Eigen::DontAlign> q(s.q.w() / norm, s.q.x() / norm,
                                                        s.q.y() / norm, s.q.z() / norm);
    out += detail::formatShortest(s.t, false);
    const Scalar vals[7] = {s.p.x(), s.p.y(), s.p.z(), q.x(), q.y(), q.z(), q.w()};
    for (Scalar v : vals) {
      out += ' ';
      out += detail::formatShortest(static_cast<double>(v), single);
    }
    out += '\n';
  }
  return out;
}

/// Writes a TUM trajectory file (see formatTum).
template <typename Scalar>
void writeTum(const std::string& path, const std::vector<TumPose<Scalar>>& poses) {
  writeFileText(path, formatTum(poses));
}

/// One-to-one association of two timestamp lists, after TUM's associate.py: all pairs with
/// |ta[i] - tb[j]| <= max_dt are candidates, taken greedily by increasing |ta[i] - tb[j]| (ties by
/// i, then j) while both sides are unused. Returns (i, j) index pairs sorted by i. The inputs need
/// not be sorted. (associate.py uses a strict '<'; here max_dt itself is allowed.)
inline std::vector<std::pair<size_t, size_t>> associateTimestamps(const std::vector<double>& ta,
                                                                  const std::vector<double>& tb,
                                                                  double max_dt) {
  if (!std::isfinite(max_dt) || max_dt < 0) {
    throw Error("associateTimestamps: max_dt must be finite and >= 0");
  }
  for (double t : ta) {
    if (!std::isfinite(t)) throw Error("associateTimestamps: non-finite timestamp in the first list");
  }
  for (double t : tb) {
    if (!std::isfinite(t)) throw Error("associateTimestamps: non-finite timestamp in the second list");
  }
  std::vector<size_t> order_b(tb.size());
  for (size_t j = 0; j < tb.size(); ++j) order_b[j] = j;
  std::sort(order_b.begin(), order_b.end(),
            [&](size_t x, size_t y) { return tb[x] < tb[y] || (tb[x] == tb[y] && x < y); });
  std::vector<std::tuple<double, size_t, size_t>> candidates;
  for (size_t i = 0; i < ta.size(); ++i) {
    // Search window widened by a few ulps; the exact test |ta - tb| <= max_dt decides.
    const double slack = 4 * std::numeric_limits<double>::epsilon() * (std::fabs(ta[i]) + max_dt);
    const auto first = std::lower_bound(order_b.begin(), order_b.end(), ta[i] - max_dt - slack,
                                        [&](size_t j, double t) { return tb[j] < t; });
    for (auto it = first; it != order_b.end() && tb[*it] <= ta[i] + max_dt + slack; ++it) {
      const double d = std::fabs(ta[i] - tb[*it]);
      if (d <= max_dt) candidates.emplace_back(d, i, *it);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<char> used_a(ta.size(), 0), used_b(tb.size(), 0);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const auto& c : candidates) {
    const size_t i = std::get<1>(c), j = std::get<2>(c);
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = 1;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

/// associateTimestamps on the timestamps of two trajectories.
template <typename Scalar>
std::vector<std::pair<size_t, size_t>> associateByTimestamp(const std::vector<TumPose<Scalar>>& a,
                                                            const std::vector<TumPose<Scalar>>& b,
                                                            double max_dt) {
  std::vector<double> ta(a.size()), tb(b.size());
  for (size_t i = 0; i < a.size(); ++i) ta[i] = a[i].t;
  for (size_t j = 0; j < b.size(); ++j) tb[j] = b[j].t;
  return associateTimestamps(ta, tb, max_dt);
}

}  // namespace hawor
