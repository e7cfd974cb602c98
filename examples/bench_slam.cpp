// bench_slam — the SLAM benchmark: every synthetic preset with and without the dual
// hand masking, one table: ATE (Sim(3)-aligned mean error, metres and % of the ground-truth path
// length), camera rotation error (degrees, mean and max after the best global rotation; defined
// also for near-pure rotation, where the positions carry no measurable motion), ms per frame
// (median, p95), keyframes, losses, frame statuses, hand coverage.
// Frames are rendered in memory (no PNG round trip) and fed to both SLAM runs in the same loop,
// so the masked/unmasked comparison sees identical images and machine load.
//
//   bench_slam [--presets a,b,..] [--frames N] [--size WxH] [--fps F] [--slam-fps F] [--seed N] [--model default|synthetic]
//              [--json FILE] [--dump PREFIX] [--masked-only] [--log] [--set NAME=VALUE,...]
//   --dump PREFIX  per preset and mode, PREFIX_<preset>_<mode>.csv: frame, ground-truth and
//                  estimated camera positions (estimate as output, not aligned), status, keyframe,
//                  hand coverage (fraction of the image), estimated camera-to-world quaternion, ground-truth one
//                  relative to the first frame (the estimate's world)
//   --fps F        the camera's frame rate (default 30); without --frames each preset keeps its
//                  duration: the same motion sampled more or less densely
//   --slam-fps F   the frame rate the SLAM is told (default: --fps), which scales its frame
//                  counts (SlamOptions::fps); --fps 60 --slam-fps 30: the 30-fps counts at 60 fps
//   --masked-only  skip the unmasked runs (quicker iterations)
//   --log          each run's diagnostics (initialisation, keyframes, losses) on stderr
//   --set NAME=VALUE,...  SlamOptions fields by name for both runs, the ablations
//                  (slam/slam_option_table.hpp; as `hawor slam --set`), e.g.
//                  --set reloc.anchors=4,sequence.headPrior=false
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include "hawor/eval/camera_metrics.hpp"
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/slam/mono_slam.hpp"
#include "hawor/slam/slam_option_table.hpp"
#include "hawor/synth/synth.hpp"

namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

struct RunStats {
  std::string preset, mode;
  int frames = 0;
  double ateM = 0, atePct = 0, pathM = 0, msMedian = 0, msP95 = 0, msMean = 0, finishMs = 0;
  double rotMeanDeg = 0, rotMaxDeg = 0;  // camera rotation error after the best global rotation
  int keyframes = 0, losses = 0, resets = 0, tracked = 0, interpolated = 0, lost = 0, relocalised = 0;
  int placeLinks = 0, placedSegments = 0;  // place recognition: links verified, segments placed by them
  double mb = 0;
  double coverage30 = 0, maxCoverage = 0;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> presets = hawor::synth::synthPresetNames();
  int frames = 0, width = 640, height = 480;
  double fps = 30, slamFps = 0;
  unsigned long seed = 1;
  std::string model = "default", jsonPath, dumpPrefix;
  bool log = false, maskedOnly = false;
  std::string settings;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_slam: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--presets") {
      presets = split(next());
    } else if (a == "--frames") {
      frames = std::stoi(next());
    } else if (a == "--fps") {
      fps = std::stod(next());
      if (!(fps > 0 && fps <= 1000)) {
        std::fprintf(stderr, "bench_slam: --fps must be in (0, 1000]\n");
        return 2;
      }
    } else if (a == "--slam-fps") {
      slamFps = std::stod(next());
    } else if (a == "--size") {
      const std::string s = next();
      if (std::sscanf(s.c_str(), "%dx%d", &width, &height) != 2) {
        std::fprintf(stderr, "bench_slam: --size expects WxH\n");
        return 2;
      }
    } else if (a == "--seed") {
      seed = std::stoul(next());
    } else if (a == "--model") {
      model = next();
    } else if (a == "--json") {
      jsonPath = next();
    } else if (a == "--dump") {
      dumpPrefix = next();
    } else if (a == "--masked-only") {
      maskedOnly = true;
    } else if (a == "--log") {
      log = true;
    } else if (a == "--set") {
      settings += (settings.empty() ? std::string() : std::string(",")) + next();
    } else {
      std::fprintf(stderr, "usage: bench_slam [--presets a,b] [--frames N] [--size WxH] [--fps F] [--slam-fps F] [--seed N] [--model default|synthetic] [--json F] [--dump PREFIX] [--masked-only] [--log] [--set NAME=VALUE,...]\n");
      return 2;
    }
  }
  try {
    hawor::SlamOptions<double> check;
    hawor::setSlamOptions(check, settings);
    check.validate();
  } catch (const hawor::Error& e) {
    std::fprintf(stderr, "bench_slam: --set: %s\n", e.what());
    return 2;
  }
  try {
    hawor::HandModel<double> right, left;
    if (model == "synthetic") {
      right = hawor::makeSyntheticHand<double>();
      left = hawor::mirrorHandModel(right);
    } else {
      std::string exe = argv[0];
      const std::size_t sl = exe.rfind('/');
      const std::string dir = sl == std::string::npos ? "." : exe.substr(0, sl);
      // build/<config>/examples/bench_slam: the build's models, else the npm package from the
      // repository root or the working folder (the figures depend on which hands are drawn).
      const std::string npm = "node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand";
      const std::vector<std::string> dirs = {dir + "/../models", dir + "/../../../" + npm, npm};
      try {
        right = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Right, dirs), hawor::HandSide::Right).model;
        left = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Left, dirs), hawor::HandSide::Left).model;
      } catch (const hawor::Error& e) {
        std::fprintf(stderr, "bench_slam: default hands not found (%s); using the synthetic hand\n", e.what());
        right = hawor::makeSyntheticHand<double>();
        left = hawor::mirrorHandModel(right);
      }
    }
    std::vector<RunStats> all;
    std::printf("%-14s %-8s %6s %9s %7s %8s %7s %7s %7s %7s %5s %5s %5s %22s %5s %6s %6s %7s\n", "preset", "mode", "frames", "ATE[m]",
                "ATE[%]", "path[m]", "rot_deg", "rot_max", "ms_med", "ms_p95", "KF", "loss", "reset", "trk/int/lost/reloc", "links", "MB", "hand30", "fin_ms");
    for (const std::string& name : presets) {
      hawor::synth::SynthOptions so;
      so.width = width;
      so.height = height;
      so.fps = fps;
      so.frames = frames;  // 0: the preset's duration at any rate
      hawor::synth::SynthSequence<double> seq(hawor::synth::findSynthPreset(name), seed, left, right, so);
      const int n = seq.numFrames();
      hawor::PinholeCamera<double> cam = seq.camera();
      hawor::SlamOptions<double> om, ou;
      hawor::setSlamOptions(om, settings);
      hawor::setSlamOptions(ou, settings);
      om.fps = ou.fps = slamFps > 0 ? slamFps : fps;
      ou.useMasks = false;
      if (log) {
        om.log = [&name](const std::string& l) { std::fprintf(stderr, "[%s masked] %s\n", name.c_str(), l.c_str()); };
        ou.log = [&name](const std::string& l) { std::fprintf(stderr, "[%s unmasked] %s\n", name.c_str(), l.c_str()); };
      }
      hawor::MonoSlam<double> masked(cam, om), plain(cam, ou);
      std::vector<double> tm, tu;
      hawor::synth::SynthFrame<double> fr;
      std::vector<hawor::Vec3<double>> gt;
      std::vector<hawor::Mat3<double>> gtR;  // camera-to-world rotations (for --dump)
      std::vector<double> coverage;
      int cov30 = 0;
      double maxCov = 0;
      for (int i = 0; i < n; ++i) {
        seq.renderFrame(i, fr);
        gt.push_back(fr.worldFromCamera.t);
        gtR.push_back(fr.worldFromCamera.R);
        coverage.push_back(fr.coverage);
        cov30 += fr.coverage >= 0.3 ? 1 : 0;
        maxCov = std::max(maxCov, fr.coverage);
        auto t0 = std::chrono::steady_clock::now();
        masked.process(fr.images.rgb, &fr.images.mask);
        auto t1 = std::chrono::steady_clock::now();
        if (!maskedOnly) plain.process(fr.images.rgb, &fr.images.mask);
        auto t2 = std::chrono::steady_clock::now();
        tm.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        tu.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
      }
      double path = 0;
      for (std::size_t i = 1; i < gt.size(); ++i) path += (gt[i] - gt[i - 1]).norm();
      for (int m = 0; m < (maskedOnly ? 1 : 2); ++m) {
        hawor::MonoSlam<double>& s = m == 0 ? masked : plain;
        const double bytes = double(s.sequenceBytes());
        auto t0 = std::chrono::steady_clock::now();
        const hawor::SlamResult<double> r = s.finish();
        auto t1 = std::chrono::steady_clock::now();
        std::vector<hawor::Vec3<double>> est;
        for (const auto& T : r.poses) est.push_back(T.translation());
        if (!dumpPrefix.empty()) {
          std::ofstream d(dumpPrefix + "_" + name + "_" + (m == 0 ? "masked" : "unmasked") + ".csv");
          d << "frame,gx,gy,gz,ex,ey,ez,status,keyframe,coverage,eqx,eqy,eqz,eqw,gqx,gqy,gqz,gqw\n";
          for (std::size_t i = 0; i < est.size(); ++i) {
            const Eigen::Quaterniond q(r.poses[i].rotationMatrix());
            // The ground truth's rotation relative to the first frame (the estimate's world).
            const Eigen::Quaterniond qg(hawor::Mat3<double>(gtR.front().transpose() * gtR[i]));
            d << i << ',' << gt[i](0) << ',' << gt[i](1) << ',' << gt[i](2) << ',' << est[i](0) << ',' << est[i](1) << ','
              << est[i](2) << ',' << int(r.status[i]) << ',' << int(r.keyframe[i]) << ',' << coverage[i] << ',' << q.x() << ','
              << q.y() << ',' << q.z() << ',' << q.w() << ',' << qg.x() << ',' << qg.y() << ',' << qg.z() << ',' << qg.w() << '\n';
          }
        }
        RunStats st;
        st.preset = name;
        st.mode = m == 0 ? "masked" : "unmasked";
        st.frames = n;
        try {
          st.ateM = hawor::ateSim3(hawor::cameraPositions(gt), hawor::cameraPositions(est)) / 1000.0;
        } catch (const hawor::Error&) {
          // Every estimated position equal (rotation-only output, pure_rotation): the limit of the
          // Sim(3) alignment as its scale goes to 0 puts them all at the ground-truth centroid.
          hawor::Vec3<double> c = hawor::Vec3<double>::Zero();
          for (const auto& g : gt) c += g;
          c /= double(gt.size());
          double e = 0;
          for (const auto& g : gt) e += (g - c).norm();
          st.ateM = e / double(gt.size());
        }
        {
          std::vector<hawor::Mat3<double>> estR;
          for (const auto& T : r.poses) estR.push_back(T.rotationMatrix());
          const hawor::RotationErrors<double> re = hawor::rotationErrors(gtR, estR);
          st.rotMeanDeg = re.mean_deg;
          st.rotMaxDeg = re.max_deg;
        }
        st.pathM = path;
        st.atePct = path > 0 ? 100.0 * st.ateM / path : 0;
        const std::vector<double>& ms = m == 0 ? tm : tu;
        st.msMedian = hawor::percentile(ms, 0.5);
        st.msP95 = hawor::percentile(ms, 0.95);
        // the mean: with a frame step the frames between tracked ones cost ~0, and the median alone hides that
        st.msMean = std::accumulate(ms.begin(), ms.end(), 0.0) / double(std::max<std::size_t>(1, ms.size()));
        st.finishMs = std::chrono::duration<double, std::milli>(t1 - t0).count();
        st.keyframes = r.numKeyframes;
        st.losses = r.numLosses;
        st.resets = r.numResets;
        st.tracked = r.count(hawor::SlamStatus::Tracked);
        st.interpolated = r.count(hawor::SlamStatus::Interpolated);
        st.lost = r.count(hawor::SlamStatus::Lost);
        st.relocalised = r.count(hawor::SlamStatus::Relocalised);
        st.placeLinks = r.numPlaceLinks;
        st.placedSegments = r.numPlacedSegments;
        st.mb = bytes / (1024.0 * 1024.0);
        st.coverage30 = double(cov30) / n;
        st.maxCoverage = maxCov;
        char counts[64];
        std::snprintf(counts, sizeof counts, "%d/%d/%d/%d", st.tracked, st.interpolated, st.lost, st.relocalised);
        std::printf("%-14s %-8s %6d %9.4f %7.3f %8.3f %7.2f %7.1f %7.2f %7.2f %5d %5d %5d %22s %5d %6.1f %6.2f %7.0f\n", name.c_str(),
                    st.mode.c_str(), n, st.ateM, st.atePct, path, st.rotMeanDeg, st.rotMaxDeg, st.msMedian, st.msP95, st.keyframes, st.losses,
                    st.resets, counts, st.placeLinks, st.mb, st.coverage30, st.finishMs);
        std::fflush(stdout);
        all.push_back(st);
      }
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    std::printf("peak RSS %.1f MB (whole benchmark process, both runs and the renderer)\n", double(ru.ru_maxrss) / 1024.0);
    if (!jsonPath.empty()) {
      std::ofstream o(jsonPath);
      o << "[\n";
      for (std::size_t i = 0; i < all.size(); ++i) {
        const RunStats& s = all[i];
        o << "  {\"preset\": \"" << s.preset << "\", \"mode\": \"" << s.mode << "\", \"frames\": " << s.frames
          << ", \"ate_m\": " << s.ateM << ", \"ate_pct\": " << s.atePct << ", \"path_m\": " << s.pathM << ", \"rot_mean_deg\": " << s.rotMeanDeg
          << ", \"rot_max_deg\": " << s.rotMaxDeg
          << ", \"ms_median\": " << s.msMedian << ", \"ms_p95\": " << s.msP95 << ", \"ms_mean\": " << s.msMean << ", \"finish_ms\": " << s.finishMs
          << ", \"keyframes\": " << s.keyframes << ", \"losses\": " << s.losses << ", \"resets\": " << s.resets
          << ", \"tracked\": " << s.tracked << ", \"interpolated\": " << s.interpolated << ", \"lost\": " << s.lost
          << ", \"relocalised\": " << s.relocalised << ", \"place_links\": " << s.placeLinks
          << ", \"placed_segments\": " << s.placedSegments << ", \"sequence_mb\": " << s.mb
          << ", \"hand_coverage_ge30_fraction\": " << s.coverage30 << ", \"max_hand_coverage\": " << s.maxCoverage << "}"
          << (i + 1 < all.size() ? ",\n" : "\n");
      }
      o << "]\n";
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_slam: %s\n", e.what());
    return 1;
  }
  return 0;
}
