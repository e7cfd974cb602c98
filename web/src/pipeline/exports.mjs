// exports.mjs: the files a pipeline result (run.mjs) is saved as, shared by the node CLI and the
// browser app (pure JavaScript, no node import). Each function returns the file's content.
//
//   resultToWorldNpz(result)    -> Uint8Array  world.npz: per hand (prefixes left_ / right_) the
//       original's world-space keys trans (T,3), rot (T,3) axis-angle, hand_pose (T,P) (P = 45
//       for MANO, 3(J-1) for other skinned hands), betas (T,B) (10 for MANO, 0 for the default
//       hand), joints_world (T,21,3), valid (T,) bool (observed), infilled (T,) bool; float64;
//       plus timestamps (T,), fps (scalar), z_up (scalar bool: the gravity-aligned world, z up;
//       else the first camera's) and origin_on_floor (scalar bool). A hand never seen holds NaN
//       with valid all false.
//   resultToHandsCamNpz(result) -> Uint8Array  hands_cam.npz: per hand cam_rot, cam_trans (T,3),
//       hand_pose (T,P), betas (T,B), joints_cam (T,21,3), keypoints2d (T,21,2) image pixels,
//       valid (T,), reproj_rms_px (T,); NaN where not observed; plus intrinsics (4,) fx fy cx cy
//       and image_size (2,): the hands file `hawor world` reads (docs/pipeline.md).
//   resultToTum(result)         -> string      camera.tum: "t tx ty tz qx qy qz qw" per frame,
//       camera-to-world, metres (the estimated metric scale applied); a header line names the
//       world (worldText).
//   resultToJson(result)        -> string      result.json: the result object itself, typed
//       arrays as plain arrays, NaN / Infinity as null.
// The .npz files are stored (uncompressed) ZIPs of .npy members, as np.savez writes them.

import { encodeNpz } from '../../tools/npz.mjs';

const f64 = (a) => (a instanceof Float64Array ? a : Float64Array.from(a ?? []));
const u8 = (a) => Uint8Array.from(a ?? [], (v) => (v ? 1 : 0));

export function resultToWorldNpz(result) {
  const T = result.frameCount;
  const list = [];
  for (const side of ['left', 'right']) {
    const h = result.hands[side];
    const p = `${side}_`;
    list.push([`${p}trans`, { data: f64(h.trans), shape: [T, 3] }]);
    list.push([`${p}rot`, { data: f64(h.rot), shape: [T, 3] }]);
    list.push([`${p}hand_pose`, { data: f64(h.handPose), shape: [T, h.handPoseCols] }]);
    list.push([`${p}betas`, { data: f64(h.betas), shape: [T, h.betaCols] }]);
    list.push([`${p}joints_world`, { data: f64(h.jointsWorld), shape: [T, 21, 3] }]);
    list.push([`${p}valid`, { data: u8(h.valid), shape: [T], bool: true }]);
    list.push([`${p}infilled`, { data: u8(h.infilled), shape: [T], bool: true }]);
  }
  list.push(['timestamps', { data: f64(result.camera.timestamps), shape: [T] }]);
  list.push(['fps', { data: Float64Array.of(result.fps), shape: [] }]);
  list.push(['z_up', { data: u8([result.world?.convention === 'z-up']), shape: [], bool: true }]);
  list.push(['origin_on_floor', { data: u8([result.world?.origin === 'floor']), shape: [], bool: true }]);
  return encodeNpz(list);
}

/** The rows of a (T, C) array at the valid frames, NaN elsewhere. */
function observedRows(a, valid, T) {
  const src = f64(a);
  const C = T ? src.length / T : 0;
  const out = new Float64Array(T * C).fill(NaN);
  for (let t = 0; t < T; ++t) if (valid[t]) out.set(src.subarray(t * C, (t + 1) * C), t * C);
  return out;
}

export function resultToHandsCamNpz(result) {
  const T = result.frameCount;
  const list = [];
  for (const side of ['left', 'right']) {
    const h = result.hands[side];
    const p = `${side}_`;
    list.push([`${p}cam_rot`, { data: f64(h.camRot), shape: [T, 3] }]);
    list.push([`${p}cam_trans`, { data: f64(h.camTrans), shape: [T, 3] }]);
    // the articulation and shape of the observed frames (the world motion's there; NaN elsewhere)
    list.push([`${p}hand_pose`, { data: observedRows(h.handPose, h.valid, T), shape: [T, h.handPoseCols] }]);
    list.push([`${p}betas`, { data: observedRows(h.betas, h.valid, T), shape: [T, h.betaCols] }]);
    list.push([`${p}joints_cam`, { data: f64(h.jointsCam), shape: [T, 21, 3] }]);
    list.push([`${p}keypoints2d`, { data: f64(h.keypoints2d), shape: [T, 21, 2] }]);
    list.push([`${p}valid`, { data: u8(h.valid), shape: [T], bool: true }]);
    list.push([`${p}reproj_rms_px`, { data: f64(h.reprojRmsPx), shape: [T] }]);
  }
  const k = result.intrinsics;
  list.push(['intrinsics', { data: Float64Array.of(k.fx, k.fy, k.cx, k.cy), shape: [4] }]);
  list.push(['image_size', { data: Float64Array.of(result.width, result.height), shape: [2] }]);
  return encodeNpz(list);
}

/** One line on the result's world (result.world; a result without one is the first camera's). */
export function worldText(world) {
  if (!world || world.convention !== 'z-up') return "the first camera's frame (x right, y down, z forward)";
  const up = world.up === 'floor' ? 'the floor plane' : "the cameras' axes";
  return `gravity-aligned, z up (from ${up}, confidence ${Number(world.upConfidence).toFixed(2)}), the first camera looking along +y, origin ${world.origin === 'floor' ? 'on the floor below the first camera' : 'at the first camera'}`;
}

export function resultToTum(result) {
  const { positions: p, quaternions: q, timestamps: ts } = result.camera;
  const lines = ['# camera-to-world, metres (hawor pipeline): t tx ty tz qx qy qz qw', `# world: ${worldText(result.world)}`];
  for (let t = 0; t < result.frameCount; ++t) {
    const row = [ts[t], p[3 * t], p[3 * t + 1], p[3 * t + 2], q[4 * t], q[4 * t + 1], q[4 * t + 2], q[4 * t + 3]];
    lines.push(row.map((v) => (Number.isFinite(v) ? Number(v.toPrecision(12)).toString() : 'nan')).join(' '));
  }
  return `${lines.join('\n')}\n`;
}

/** JSON text of the result: typed arrays as arrays, non-finite numbers as null. */
export function resultToJson(result, space = 0) {
  return JSON.stringify(result, (key, v) => {
    if (ArrayBuffer.isView(v)) return Array.from(v, (x) => (Number.isFinite(x) ? x : null));
    if (typeof v === 'number' && !Number.isFinite(v)) return null;
    return v;
  }, space);
}
