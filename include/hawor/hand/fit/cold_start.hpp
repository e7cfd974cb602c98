// hawor/hand/fit/cold_start.hpp — HandFitter's cold start: the palm's rotation and metric
// translation from the landmarks (or a PnP from 24 orientations without them), swing-only IK of
// the fingers, the palm centroid placed (steps 1–4 of hand/fit.hpp's file comment).
// Member functions of HandFitter (hand/fit.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../fit.hpp"

namespace hawor {

template <typename Scalar>
void HandFitter<Scalar>::coldInit(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam, const HandFitOptions<Scalar>& opt) {
  const int K = km_.K;
  cur_.w.setZero();
  if (prev_) {
    cur_.beta = prevBeta_;
  } else {
    cur_.beta.setZero();
  }
  cur_.R0.setIdentity();
  cur_.t.setZero();
  PnPOptions<Scalar> po;
  po.loss = opt.loss == RobustLoss::None ? RobustLoss::Huber : opt.loss;
  po.sigmaPx = opt.sigmaPx;
  po.robustScale = opt.robustScale;
  // Points usable for the palm rotation: palm keypoints with 3D confidence.
  std::vector<int> palm;
  for (int k : palm_)
    if (w3_(k) > Scalar(0)) palm.push_back(k);
  const bool has3d = sum3_ > Scalar(0) && n3_ >= 3;
  if (has3d && palm.size() < 3) {
    palm.clear();
    for (int k = 0; k < K; ++k)
      if (w3_(k) > Scalar(0)) palm.push_back(k);
  }
  // Rest keypoints at the initial shape.
  evaluateHandKeypoints(km_, Mat3<Scalar>(Mat3<Scalar>::Identity()), cur_.w, cur_.beta,
                        Vec3<Scalar>(Vec3<Scalar>::Zero()), kws_, kp_);
  const Vec3<Scalar> J0 = kws_.gPos[0];
  if (has3d) {
    Points3<Scalar> src(static_cast<Eigen::Index>(palm.size()), 3), dst(static_cast<Eigen::Index>(palm.size()), 3);
    VecX<Scalar> wt(static_cast<Eigen::Index>(palm.size()));
    for (std::size_t i = 0; i < palm.size(); ++i) {
      src.row(static_cast<Eigen::Index>(i)) = kp_.row(palm[i]);
      dst.row(static_cast<Eigen::Index>(i)) = obs.keypoints3d.row(palm[i]);
      wt(static_cast<Eigen::Index>(i)) = w3_(palm[i]);
    }
    cur_.R0 = umeyama(src, dst, true, &wt).R;
    // Metric PnP of the landmarks (camera-aligned: R = I unless refined).
    Points3<Scalar> X(K, 3);
    Pixels<Scalar> uv(K, 2);
    VecX<Scalar> c(K);
    for (int k = 0; k < K; ++k) {
      X.row(k) = obs.keypoints3d.row(k);
      uv.row(k) = obs.keypoints2d.row(k);
      c(k) = (w3_(k) > Scalar(0)) ? w2_(k) : Scalar(0);
    }
    po.refineRotation = opt.refinePnPRotation;
    const PnPResult<Scalar> pr = solvePnPMetric(X, uv, &c, cam, Mat3<Scalar>(Mat3<Scalar>::Identity()), po);
    if (!pr.ok) throw Error("hand fit: cold start failed (metric PnP found no pose in front of the camera)");
    cur_.R0 = pr.R * cur_.R0;
    Y_.resize(K, 3);
    for (int k = 0; k < K; ++k) Y_.row(k) = (pr.R * obs.keypoints3d.row(k).transpose() + pr.t).transpose();
    swingIk();
    placeTranslation(palm);
  } else {
    // No 3D landmarks: rotation and translation PnP of the rest palm from 24 orientations.
    std::vector<int> pts;
    for (int k : palm_)
      if (w2_(k) > Scalar(0)) pts.push_back(k);
    if (pts.size() < 3) {
      pts.clear();
      for (int k = 0; k < K; ++k)
        if (w2_(k) > Scalar(0)) pts.push_back(k);
    }
    if (pts.size() < 3) throw Error("hand fit: cold start needs 3 keypoints with confidence > 0");
    Points3<Scalar> X(static_cast<Eigen::Index>(pts.size()), 3);
    Pixels<Scalar> uv(static_cast<Eigen::Index>(pts.size()), 2);
    VecX<Scalar> c(static_cast<Eigen::Index>(pts.size()));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      X.row(static_cast<Eigen::Index>(i)) = kp_.row(pts[i]) - J0.transpose();
      uv.row(static_cast<Eigen::Index>(i)) = obs.keypoints2d.row(pts[i]);
      c(static_cast<Eigen::Index>(i)) = w2_(pts[i]);
    }
    po.refineRotation = true;
    po.maxIterations = 30;
    PnPResult<Scalar> best;
    Scalar bestRms = std::numeric_limits<Scalar>::infinity();
    const Scalar h = Constants<Scalar>::pi() / Scalar(2);
    const Vec3<Scalar> faces[6] = {Vec3<Scalar>(0, 0, 0), Vec3<Scalar>(h, 0, 0), Vec3<Scalar>(-h, 0, 0),
                                   Vec3<Scalar>(0, h, 0), Vec3<Scalar>(0, -h, 0), Vec3<Scalar>(2 * h, 0, 0)};
    for (const Vec3<Scalar>& f : faces) {
      for (int q = 0; q < 4; ++q) {
        const Mat3<Scalar> R = axisAngleToMatrix(Vec3<Scalar>(Scalar(0), Scalar(0), Scalar(q) * h)) * axisAngleToMatrix(f);
        const PnPResult<Scalar> pr = solvePnPMetric(X, uv, &c, cam, R, po);
        if (pr.ok && pr.rmsPx < bestRms) {
          bestRms = pr.rmsPx;
          best = pr;
        }
      }
    }
    if (!best.ok) throw Error("hand fit: cold start failed (no pose in front of the camera)");
    cur_.R0 = best.R;
    // p = R (x − J0) + t_pnp = R (x − J0) + J0 + transl.
    cur_.t = best.t - J0;
  }
}

// Swing-only IK on the camera-frame landmarks Y_: each bone (joint → next keypoint) is turned
// by the smallest rotation that aligns it with the landmarks' bone, root to tip.
template <typename Scalar>
void HandFitter<Scalar>::swingIk() {
  for (const IkLink& l : ikChain_) {
    if (!(w3_(l.kp) > Scalar(0)) || !(w3_(l.next) > Scalar(0))) continue;
    evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, cur_.t, kws_, kp_);
    const Vec3<Scalar> a = (kp_.row(l.next) - kp_.row(l.kp)).transpose();
    const Vec3<Scalar> b = (Y_.row(l.next) - Y_.row(l.kp)).transpose();
    const Scalar na = a.norm(), nb = b.norm();
    if (!(na > Scalar(0)) || !(nb > Scalar(0))) continue;
    const Vec3<Scalar> an = a / na, bn = b / nb;
    const Vec3<Scalar> axis = an.cross(bn);
    const Scalar s = axis.norm(), c = an.dot(bn);
    if (!(s > Scalar(1e-9))) continue;
    const Scalar ang = std::atan2(s, c);
    const Mat3<Scalar> Ralign = axisAngleToMatrix(Vec3<Scalar>(axis * (ang / s)));
    const std::size_t j = static_cast<std::size_t>(l.joint);
    const std::size_t p = static_cast<std::size_t>(km_.parents[j]);
    // New local rotation: Rg_pᵀ · R_align · Rg_j.
    const Mat3<Scalar> Rj = kws_.gRot[p].transpose() * Ralign * kws_.gRot[j];
    Vec3<Scalar> w = matrixToAxisAngle(Rj);
    // Keep the swing inside the joint's range (the LM refines; this only avoids a bad start).
    const JointRange<Scalar>& r = limits_.ranges[j];
    Vec3<Scalar> an3 = limits_.anatomical(l.joint, w);
    for (int q = 0; q < 3; ++q) an3(q) = std::min(std::max(an3(q), r.lo(q)), r.hi(q));
    w = limits_.axisAngle(l.joint, an3);
    cur_.w.row(l.joint - 1) = w.transpose();
  }
}

// t such that the model's palm centroid (current pose) lands on the landmarks' (Y_).
template <typename Scalar>
void HandFitter<Scalar>::placeTranslation(const std::vector<int>& palm) {
  evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, Vec3<Scalar>(Vec3<Scalar>::Zero()), kws_, kp_);
  Vec3<Scalar> a = Vec3<Scalar>::Zero(), b = Vec3<Scalar>::Zero();
  Scalar ws = Scalar(0);
  for (int k : palm) {
    a += w3_(k) * kp_.row(k).transpose();
    b += w3_(k) * Y_.row(k).transpose();
    ws += w3_(k);
  }
  cur_.t = (b - a) / ws;
}

}  // namespace hawor
