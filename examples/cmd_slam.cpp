// hawor slam — monocular SLAM with dual hand masking over a folder of frames
// (include/hawor/slam/mono_slam.hpp). Reads the images in name order, masks of the same names.
// With a lens (--camera), frames and masks are rectified to the virtual pinhole camera with the
// same intrinsics (render/rectify.hpp) before the SLAM sees them.
#include <sys/resource.h>

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
#include "hawor/render/rectify.hpp"
#include "hawor/render/resample.hpp"
#include "hawor/slam/mono_slam.hpp"
#include "hawor/slam/slam_option_table.hpp"

namespace hawor_cli {
namespace {

const char* kSlamHelp =
    "usage: hawor slam --images DIR --intrinsics fx,fy,cx,cy [--camera LENS] [--masks DIR]\n"
    "                  [--no-mask] --out TRAJ.tum [--keyframe-depths KD.npz] [--stats STATS.json]\n"
    "                  [--fps F] [--readout S] [--max-frames N] [--refine-focal [--focal-prior S]]\n"
    "                  [--set NAME=VALUE,...] [--verbose]\n"
    "\n"
    "Sparse monocular SLAM (KLT tracks, PnP, keyframes, sliding-window and global bundle\n"
    "adjustment) with the hands masked out of the front end and the bundle adjustment.\n"
    "\n"
    "  --images DIR          frames (.png/.jpg/.bmp), processed in file-name order\n"
    "  --intrinsics fx,fy,cx,cy  intrinsics in pixels (pixel centres at integers)\n"
    "  --camera LENS         the lens: pinhole (default), opencv:k1,k2,p1,p2[,k3] or\n"
    "                        fisheye:k1,k2,k3,k4 (the second line of a hawor synth\n"
    "                        intrinsics.txt); frames (bilinear) and masks (nearest) are rectified\n"
    "                        to the pinhole camera with the same intrinsics, which the SLAM runs\n"
    "                        on (a fisheye's periphery beyond its field is cut); the poses are the\n"
    "                        real camera's, --keyframe-depths pixels are the rectified image's\n"
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
    "  --fps F               the frame rate (default 30): timestamps, and the SLAM's frame counts\n"
    "                        and per-frame angles, stated for 30 fps, applied at F\n"
    "  --readout S           rolling shutter: seconds from the first row's exposure to the\n"
    "                        last's (a phone at 1080p: 0.015-0.03; default 0, a global\n"
    "                        shutter; negative: rows read bottom to top, as in a clip played\n"
    "                        backwards); at most 1/fps. The tracked points are brought to the\n"
    "                        middle row's time under the head's rotation (with --camera: the\n"
    "                        rectified image's rows, an approximation)\n"
    "  --max-frames N        only the first N frames\n"
    "  --refine-focal        self-calibrate the focal (fx, fy by one factor) in the final bundle\n"
    "                        adjustment where the motion determines it; the --intrinsics focal\n"
    "                        is the guess (the trajectory then uses the refined focal)\n"
    "  --focal-prior S       std of log(f / guess) of the guess (default 0.3, a FOV guess)\n"
    "  --set NAME=VALUE,...  set SlamOptions fields by name, for ablations (for example\n"
    "                        --set init.minRotationDeg=9,reloc.anchors=4; twoView.NAME for\n"
    "                        the initialisation's); an unknown name lists the known ones;\n"
    "                        may be repeated\n"
    "  --verbose             one line per frame on stderr, and the SLAM's events (initialisation,\n"
    "                        PnP, keyframes, losses)\n"
    "\n"
    "Prints one JSON object: frames, keyframes, tracked, interpolated, lost, relocalised,\n"
    "losses, resets, relocalisations, place_relocalisations, initialised, camera,\n"
    "rectified_outside (pixels of the rectified image the lens does not see),\n"
    "median_ms_per_frame and p95_ms_per_frame (with the rectification), and\n"
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
                  {"images", "intrinsics", "camera", "masks", "out", "keyframe-depths", "stats", "fps", "readout", "max-frames",
                   "focal-prior", "set"},
                  {"no-mask", "verbose", "refine-focal"});
  if (args.help()) {
    std::fputs(kSlamHelp, stdout);
    return 0;
  }
  const std::string dir = args.required("images");
  const std::vector<double> k = parseList(args.required("intrinsics"), "--intrinsics");
  if (k.size() != 4 || !(k[0] > 0) || !(k[1] > 0)) throw UsageError("--intrinsics expects fx,fy,cx,cy with fx, fy > 0");
  hawor::Lens<double> lens;
  try {
    lens = hawor::Lens<double>::parse(args.get("camera", "pinhole"));
  } catch (const hawor::Error& e) {
    throw UsageError(std::string("--camera: ") + (e.what() + 7));  // without "hawor: "
  }
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
  const double readout = args.number("readout", 0.0);
  if (!(std::abs(readout) <= 1.0 / fps)) throw UsageError("--readout must be between -1/fps and 1/fps seconds");
  opt.rollingShutter = readout * fps;
  opt.fps = fps;
  opt.finish.refineFocal = args.flag("refine-focal");
  if (args.has("focal-prior")) {
    if (!opt.finish.refineFocal) throw UsageError("--focal-prior needs --refine-focal");
    opt.focal.priorSigmaLog = args.number("focal-prior", 0.3);
    if (!(opt.focal.priorSigmaLog > 0)) throw UsageError("--focal-prior must be > 0");
  }
  try {
    for (const std::string& s : args.all("set")) hawor::setSlamOptions(opt, s);  // repeated --set: all of them, in order
    opt.validate();  // a bad value or combination is the user's, named before any frame is read
  } catch (const hawor::Error& e) {
    throw UsageError(std::string("--set: ") + (e.what() + 7));  // without "hawor: "
  }
  const bool verbose = args.flag("verbose");
  if (verbose) opt.log = [](const std::string& line) { std::fprintf(stderr, "slam: %s\n", line.c_str()); };
  hawor::MonoSlam<double> slam(cam, opt);
  // The lens: rectification to the pinhole camera with the same intrinsics and size (an exact
  // no-op for a pinhole lens), sized from the first frame.
  hawor::ImageU8 first = hawor::readImage(dir + "/" + names[0]);
  hawor::CameraModel<double> model{cam, lens};
  model.intrinsics.width = first.width, model.intrinsics.height = first.height;
  try {
    model.validate();
  } catch (const hawor::Error& e) {
    throw UsageError(std::string("--camera ") + args.get("camera", "pinhole") + " with --intrinsics on " +
                     std::to_string(first.width) + "x" + std::to_string(first.height) + " frames: " + (e.what() + 7));
  }
  const hawor::RectifyMap<double> rectify(model);
  hawor::ImageU8 grey, rectImage, rectMask, slamMask;
  std::vector<double> ms;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const hawor::ImageU8 img = i == 0 ? std::move(first) : hawor::readImage(dir + "/" + names[i]);
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
      if (rectify.identity()) {
        st = slam.process(img, haveMask ? &mask : nullptr);
      } else {
        if (img.width != model.intrinsics.width || img.height != model.intrinsics.height) {
          throw hawor::Error("the frame is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             " but the first frame was " + std::to_string(model.intrinsics.width) + "x" +
                             std::to_string(model.intrinsics.height));
        }
        // grey first (one channel to resample), then the remap; the mask by nearest pixel, with
        // the region the lens does not see added (no corners on its edge)
        grey = img.channels == 1 ? img : hawor::downscaleBox(img, img.width, img.height, true);
        rectImage = rectify.remapBilinear(grey);
        if (haveMask) rectMask = rectify.remapNearest(mask);
        const bool useMask = rectify.needsSlamMask(haveMask ? rectMask.data.data() : nullptr);
        if (useMask) {
          slamMask.resize(rectify.width(), rectify.height(), 1);
          rectify.slamMask(haveMask ? rectMask.data.data() : nullptr, slamMask.data.data());
        }
        st = slam.process(rectImage, useMask ? &slamMask : nullptr);
      }
    } catch (const hawor::Error& e) {
      throw hawor::Error(names[i] + ": " + e.what());
    }
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (verbose) {
      std::fprintf(stderr, "frame %zu %s tracks=%d keyframes=%d %.1f ms\n", i, hawor::slamStatusName(st),
                   slam.numLiveTracks(), slam.numKeyframes(), ms.back());
    }
  }
  const auto tFinish = std::chrono::steady_clock::now();
  const hawor::SlamResult<double> r = slam.finish();
  const double finishMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tFinish).count();
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);  // ru_maxrss: the process' peak resident memory, KiB on Linux
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
  std::string links = "[";  // [frame, older frame, matched points] per place link
  for (const auto& l : r.placeLinks) {
    links += (links.size() > 1 ? ", [" : "[") + std::to_string(l.frame) + ", " + std::to_string(l.oldFrame) + ", " +
             std::to_string(l.points) + "]";
  }
  links += "]";
  JsonObject j;
  j.integer("frames", static_cast<long long>(r.poses.size()))
      .integer("keyframes", r.numKeyframes)
      .integer("adjusted_keyframes", r.numAdjustedKeyframes)
      .integer("tracked", r.count(hawor::SlamStatus::Tracked))
      .integer("interpolated", r.count(hawor::SlamStatus::Interpolated))
      .integer("lost", r.count(hawor::SlamStatus::Lost))
      .integer("relocalised", r.count(hawor::SlamStatus::Relocalised))
      .integer("losses", r.numLosses)
      .integer("resets", r.numResets)
      .integer("relocalisations", r.numRelocalisations)
      .integer("place_relocalisations", r.numPlaceRelocalisations)
      .integer("revisit_points", r.numRevisitPoints)
      .integer("place_links", r.numPlaceLinks)
      .raw("place_link_frames", links)
      .integer("placed_segments", r.numPlacedSegments)
      .integer("refined_frames", r.numRefinedFrames)
      .integer("head_model_frames", r.numHeadModelFrames)
      .raw("initialised", r.initialised ? "true" : "false")
      .raw("masked", useMasks ? "true" : "false")
      .str("camera", lens.toString())
      .integer("rectified_outside", static_cast<long long>(rectify.numOutside()))
      .num("median_ms_per_frame", hawor::percentile(ms, 0.5))
      .num("p95_ms_per_frame", hawor::percentile(ms, 0.95))
      .num("finish_ms", finishMs)
      .num("peak_rss_mb", double(ru.ru_maxrss) / 1024.0);
  if (opt.finish.refineFocal) {
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
