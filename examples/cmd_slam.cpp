// hawor slam — monocular SLAM with dual hand masking over a folder of frames
// (include/hawor/slam/mono_slam.hpp). Reads the images in name order, masks of the same names.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "commands.hpp"
#include "hawor/io/file.hpp"
#include "hawor/io/image_file.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"
#include "hawor/slam/mono_slam.hpp"

namespace hawor_cli {
namespace {

const char* kSlamHelp =
    "usage: hawor slam --images DIR --intrinsics fx,fy,cx,cy [--masks DIR] [--no-mask]\n"
    "                  --out TRAJ.tum [--keyframe-depths KD.npz] [--stats STATS.json]\n"
    "                  [--fps F] [--max-frames N] [--refine-focal [--focal-prior S]] [--verbose]\n"
    "\n"
    "Sparse monocular SLAM (KLT tracks, PnP, keyframes, sliding-window and global bundle\n"
    "adjustment) with the hands masked out of the front end and the bundle adjustment.\n"
    "\n"
    "  --images DIR          frames (.png/.jpg/.bmp), processed in file-name order\n"
    "  --intrinsics fx,fy,cx,cy  pinhole intrinsics in pixels (pixel centres at integers)\n"
    "  --masks DIR           hand masks, PNGs named like the frames (hand pixels non-zero);\n"
    "                        a frame without a mask file has no hands\n"
    "  --no-mask             ignore --masks (the unmasked ablation)\n"
    "  --out TRAJ.tum        camera-to-world poses, world = first frame's camera, monocular\n"
    "                        scale; timestamps frame / fps\n"
    "  --keyframe-depths KD.npz  sparse depths for the scale step: frames (K,) int32 keyframe\n"
    "                        frame indices, kf (N,) int32 row of frames per point, uv (N,2)\n"
    "                        pixels, depth (N,) along the optical axis (map units)\n"
    "  --stats STATS.json    per-frame status (tracked|interpolated|lost|relocalised),\n"
    "                        keyframe flags, PnP inliers and ms, plus totals\n"
    "  --fps F               timestamps (default 30)\n"
    "  --max-frames N        only the first N frames\n"
    "  --refine-focal        self-calibrate the focal (fx, fy by one factor) in the final bundle\n"
    "                        adjustment where the motion determines it; the --intrinsics focal\n"
    "                        is the guess (the trajectory then uses the refined focal)\n"
    "  --focal-prior S       std of log(f / guess) of the guess (default 0.3, a FOV guess)\n"
    "  --verbose             one line per frame on stderr, and the SLAM's events (initialisation,\n"
    "                        PnP, keyframes, losses)\n"
    "\n"
    "Prints one JSON object: frames, keyframes, tracked, interpolated, lost, relocalised,\n"
    "losses, resets, relocalisations, initialised, median_ms_per_frame, p95_ms_per_frame, and\n"
    "with --refine-focal: focal_fx (the focal used), focal_guess_fx, focal_refined, focal_std\n"
    "(posterior std of log f, null when declined) and focal_reason.\n";

std::vector<double> parseList(const std::string& s, const std::string& what) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (tok.empty() || *end != '\0' || !std::isfinite(x)) throw UsageError(what + ": '" + tok + "' is not a number");
    v.push_back(x);
  }
  return v;
}

bool fileExists(const std::string& p) {
  std::FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) return false;
  std::fclose(f);
  return true;
}

}  // namespace

int cmdSlam(int argc, char** argv) {
  const Args args(argc, argv, 2,
                  {"images", "intrinsics", "masks", "out", "keyframe-depths", "stats", "fps", "max-frames", "focal-prior"},
                  {"no-mask", "verbose", "refine-focal"});
  if (args.help()) {
    std::fputs(kSlamHelp, stdout);
    return 0;
  }
  const std::string dir = args.required("images");
  const std::vector<double> k = parseList(args.required("intrinsics"), "--intrinsics");
  if (k.size() != 4 || !(k[0] > 0) || !(k[1] > 0)) throw UsageError("--intrinsics expects fx,fy,cx,cy with fx, fy > 0");
  const std::string out = args.required("out");
  const double fps = args.number("fps", 30.0);
  if (!(fps > 0)) throw UsageError("--fps must be > 0");
  const bool useMasks = args.has("masks") && !args.flag("no-mask");
  const std::string maskDir = args.get("masks", "");
  std::vector<std::string> names = hawor::listImageFiles(dir);
  if (args.has("max-frames")) {
    const double m = args.number("max-frames", 0);
    if (!(m >= 1)) throw UsageError("--max-frames must be >= 1");
    if (names.size() > static_cast<std::size_t>(m)) names.resize(static_cast<std::size_t>(m));
  }
  if (names.size() < 2) {
    throw hawor::Error("--images " + dir + ": need at least 2 images (.png/.jpg/.bmp), found " + std::to_string(names.size()));
  }
  hawor::PinholeCamera<double> cam;
  cam.fx = k[0], cam.fy = k[1], cam.cx = k[2], cam.cy = k[3];
  hawor::SlamOptions<double> opt;
  opt.useMasks = useMasks;
  opt.refineFocal = args.flag("refine-focal");
  if (args.has("focal-prior")) {
    if (!opt.refineFocal) throw UsageError("--focal-prior needs --refine-focal");
    opt.focal.priorSigmaLog = args.number("focal-prior", 0.3);
    if (!(opt.focal.priorSigmaLog > 0)) throw UsageError("--focal-prior must be > 0");
  }
  const bool verbose = args.flag("verbose");
  if (verbose) opt.log = [](const std::string& line) { std::fprintf(stderr, "slam: %s\n", line.c_str()); };
  hawor::MonoSlam<double> slam(cam, opt);
  std::vector<double> ms;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const hawor::ImageU8 img = hawor::readImage(dir + "/" + names[i]);
    if (i == 0) {
      cam.width = img.width, cam.height = img.height;
    }
    hawor::ImageU8 mask;
    bool haveMask = false;
    if (useMasks) {
      std::string mp = maskDir + "/" + names[i];
      if (!fileExists(mp)) {
        const std::size_t dot = names[i].rfind('.');
        mp = maskDir + "/" + names[i].substr(0, dot) + ".png";
      }
      if (fileExists(mp)) {
        mask = hawor::readImage(mp, 1);
        if (mask.width != img.width || mask.height != img.height) {
          throw hawor::Error("mask " + mp + " is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                             " but frame " + names[i] + " is " + std::to_string(img.width) + "x" + std::to_string(img.height));
        }
        haveMask = true;
      }
    }
    const auto t0 = std::chrono::steady_clock::now();
    hawor::SlamStatus st;
    try {
      st = slam.process(img, haveMask ? &mask : nullptr);
    } catch (const hawor::Error& e) {
      throw hawor::Error(names[i] + ": " + e.what());
    }
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (verbose) {
      std::fprintf(stderr, "frame %zu %s tracks=%d keyframes=%d %.1f ms\n", i, hawor::slamStatusName(st),
                   slam.numLiveTracks(), slam.numKeyframes(), ms.back());
    }
  }
  const hawor::SlamResult<double> r = slam.finish();
  std::vector<hawor::TumPose<double>> traj;
  for (std::size_t i = 0; i < r.poses.size(); ++i) {
    hawor::TumPose<double> p;
    p.t = double(i) / fps;
    p.p = r.poses[i].translation();
    p.q = Eigen::Quaterniond(r.poses[i].rotationMatrix());
    traj.push_back(p);
  }
  hawor::writeTum(out, traj);
  if (args.has("keyframe-depths")) {
    std::vector<std::int32_t> frames, kf;
    std::vector<double> uv, depth;
    for (std::size_t j = 0; j < r.keyframeDepths.size(); ++j) {
      const auto& d = r.keyframeDepths[j];
      frames.push_back(d.frame);
      for (std::size_t q = 0; q < d.depth.size(); ++q) {
        kf.push_back(static_cast<std::int32_t>(j));
        uv.push_back(d.uv[q](0));
        uv.push_back(d.uv[q](1));
        depth.push_back(d.depth[q]);
      }
    }
    hawor::Npz z;
    z.set("frames", hawor::NpyArray::fromVector(frames));
    z.set("kf", hawor::NpyArray::fromVector(kf));
    z.set("uv", hawor::NpyArray::fromData(uv.data(), {depth.size(), 2}));
    z.set("depth", hawor::NpyArray::fromVector(depth));
    z.write(args.required("keyframe-depths"));
  }
  JsonObject j;
  j.integer("frames", static_cast<long long>(r.poses.size()))
      .integer("keyframes", r.numKeyframes)
      .integer("tracked", r.count(hawor::SlamStatus::Tracked))
      .integer("interpolated", r.count(hawor::SlamStatus::Interpolated))
      .integer("lost", r.count(hawor::SlamStatus::Lost))
      .integer("relocalised", r.count(hawor::SlamStatus::Relocalised))
      .integer("losses", r.numLosses)
      .integer("resets", r.numResets)
      .integer("relocalisations", r.numRelocalisations)
      .integer("revisit_points", r.numRevisitPoints)
      .integer("refined_frames", r.numRefinedFrames)
      .integer("head_model_frames", r.numHeadModelFrames)
      .raw("initialised", r.initialised ? "true" : "false")
      .raw("masked", useMasks ? "true" : "false")
      .num("median_ms_per_frame", hawor::percentile(ms, 0.5))
      .num("p95_ms_per_frame", hawor::percentile(ms, 0.95));
  if (opt.refineFocal) {
    j.num("focal_fx", r.camera.fx)
        .num("focal_guess_fx", r.focal.guessFx)
        .raw("focal_refined", r.focal.changed ? "true" : "false")
        .num("focal_std", r.focal.accepted ? double(r.focal.stdLog) : std::nan(""))
        .str("focal_reason", r.focal.reason);
  }
  if (args.has("stats")) {
    std::string s = "{\"summary\": " + j.dump() + ", \"status\": [";
    for (std::size_t i = 0; i < r.status.size(); ++i) s += std::string(i ? ", " : "") + "\"" + hawor::slamStatusName(r.status[i]) + "\"";
    s += "], \"keyframe\": [";
    for (std::size_t i = 0; i < r.keyframe.size(); ++i) s += std::string(i ? ", " : "") + (r.keyframe[i] ? "1" : "0");
    s += "], \"inliers\": [";
    for (std::size_t i = 0; i < r.inliers.size(); ++i) s += std::string(i ? ", " : "") + std::to_string(r.inliers[i]);
    s += "], \"ms\": [";
    for (std::size_t i = 0; i < ms.size(); ++i) {
      char b[32];
      std::snprintf(b, sizeof b, "%s%.3f", i ? ", " : "", ms[i]);
      s += b;
    }
    s += "]}\n";
    hawor::writeFileText(args.required("stats"), s);
  }
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace hawor_cli
