// geometry.mjs: rotated regions of interest (ROIs), the crops the hand networks see, and the
// mapping of network coordinates back to the image. Pure JavaScript on typed arrays, shared by
// the browser app and node.
//
// Conventions (docs/design.md §2): image pixels, origin top-left, pixel centres at integer coordinates,
// so the image spans [-0.5, W-0.5] x [-0.5, H-0.5]. A ROI is { cx, cy, w, h, rotation } in
// pixels and radians: the crop's normalised point (u, v) in [-0.5, 0.5]^2 (u right, v down) is
// the image point
//   x = cx + u w cos(r) - v h sin(r),   y = cy + u w sin(r) + v h cos(r)
// (MediaPipe's NormalizedRect with the same rotation, converted to pixels: X = x_norm W - 0.5).
// A crop of N x N pixels covers the ROI edge to edge: crop pixel (i, j) has u = (i + 0.5)/N - 0.5.

/** angle wrapped to [-pi, pi). */
export function normalizeRadians(a) {
  return a - 2 * Math.PI * Math.floor((a + Math.PI) / (2 * Math.PI));
}

/** Crop-normalised (u, v) in [-0.5, 0.5] -> image pixel [x, y]. */
export function cropToImage(roi, u, v) {
  const c = Math.cos(roi.rotation);
  const s = Math.sin(roi.rotation);
  const a = u * roi.w;
  const b = v * roi.h;
  return [roi.cx + a * c - b * s, roi.cy + a * s + b * c];
}

/** Image pixel (x, y) -> crop-normalised [u, v] (the inverse of cropToImage). */
export function imageToCrop(roi, x, y) {
  const c = Math.cos(roi.rotation);
  const s = Math.sin(roi.rotation);
  const dx = x - roi.cx;
  const dy = y - roi.cy;
  return [(dx * c + dy * s) / roi.w, (-dx * s + dy * c) / roi.h];
}

/** MediaPipe's RectTransformation on a pixel ROI: shift along the ROI's own axes (in units of
 *  its width/height), then square on the long side, then scale. */
export function transformRoi(roi, { scale = 1, shiftX = 0, shiftY = 0, squareLong = true }) {
  const c = Math.cos(roi.rotation);
  const s = Math.sin(roi.rotation);
  const cx = roi.cx + roi.w * shiftX * c - roi.h * shiftY * s;
  const cy = roi.cy + roi.w * shiftX * s + roi.h * shiftY * c;
  let { w, h } = roi;
  if (squareLong) w = h = Math.max(w, h);
  return { cx, cy, w: w * scale, h: h * scale, rotation: roi.rotation };
}

/** The square ROI that letterboxes the whole image (no rotation): the palm detector's view. */
export function letterboxRoi(width, height) {
  const side = Math.max(width, height);
  return { cx: (width - 1) / 2, cy: (height - 1) / 2, w: side, h: side, rotation: 0 };
}

/**
 * One bilinear sample of an 8-bit RGB(A) image at (x, y) (pixel centres at integers) into
 * out[o..o+2] as RGB in 0..1; a neighbour outside the image reads black, or (replicate) the
 * nearest edge pixel.
 */
function sampleBilinear(data, W, H, ch, x, y, replicate, out, o) {
  const xf = Math.floor(x);
  const yf = Math.floor(y);
  const fx = x - xf;
  const fy = y - yf;
  let r = 0;
  let g = 0;
  let b = 0;
  for (let q = 0; q < 4; ++q) {
    let xx = xf + (q & 1);
    let yy = yf + (q >> 1);
    if (xx < 0 || yy < 0 || xx >= W || yy >= H) {
      if (!replicate) continue;
      xx = Math.min(Math.max(xx, 0), W - 1);
      yy = Math.min(Math.max(yy, 0), H - 1);
    }
    const wgt = ((q & 1) ? fx : 1 - fx) * ((q >> 1) ? fy : 1 - fy);
    if (wgt === 0) continue;
    const i = (yy * W + xx) * ch;
    r += wgt * data[i];
    g += wgt * data[i + 1];
    b += wgt * data[i + 2];
  }
  const k = 1 / 255;
  out[o] = r * k;
  out[o + 1] = g * k;
  out[o + 2] = b * k;
}

/**
 * Samples an N x N (or outW x outH) crop of `image` over `roi`, bilinearly, into NHWC float RGB
 * in 0..1 (what the MediaPipe networks take). Outside the image: `border` 'zero' reads black
 * (MediaPipe's palm letterbox), 'replicate' the nearest edge pixel (MediaPipe's default, used for
 * the landmark crops).
 * @param image {width, height, data: Uint8Array | Uint8ClampedArray, channels: 3 (RGB) or 4 (RGBA)}
 * @param out   optional Float32Array of outW * outH * 3 to fill
 */
export function cropImage(image, roi, outW, outH = outW, out = new Float32Array(outW * outH * 3), border = 'zero') {
  if (border !== 'zero' && border !== 'replicate') throw new Error(`cropImage: border '${border}' (zero or replicate)`);
  const replicate = border === 'replicate';
  const { width: W, height: H, data } = image;
  const ch = image.channels ?? 4;
  if (ch !== 3 && ch !== 4) throw new Error(`cropImage: ${ch} channels (3 = RGB or 4 = RGBA expected)`);
  if (data.length < W * H * ch) throw new Error(`cropImage: ${data.length} bytes for a ${W}x${H}x${ch} image`);
  if (out.length !== outW * outH * 3) throw new Error(`cropImage: output of ${out.length} floats for ${outW}x${outH}x3`);
  const c = Math.cos(roi.rotation);
  const s = Math.sin(roi.rotation);
  // x = cx + u w c - v h s with u = (i + 0.5)/outW - 0.5: linear in i and j
  const dxi = (roi.w / outW) * c;
  const dyi = (roi.w / outW) * s;
  const dxj = -(roi.h / outH) * s;
  const dyj = (roi.h / outH) * c;
  const u0 = 0.5 / outW - 0.5;
  const v0 = 0.5 / outH - 0.5;
  const x00 = roi.cx + u0 * roi.w * c - v0 * roi.h * s;
  const y00 = roi.cy + u0 * roi.w * s + v0 * roi.h * c;
  let o = 0;
  for (let j = 0; j < outH; ++j) {
    let x = x00 + j * dxj;
    let y = y00 + j * dyj;
    for (let i = 0; i < outW; ++i, x += dxi, y += dyi, o += 3) sampleBilinear(data, W, H, ch, x, y, replicate, out, o);
  }
  return out;
}

/**
 * Samples an outW x outH crop of `image` at the source pixels `map` gives (map[2 (j outW + i)],
 * [+1] = x, y of crop pixel (i, j); NaN = nothing there, read black), bilinearly, into NHWC
 * float RGB in 0..1, with cropImage's conventions and borders. The perspective crops through a
 * lens: the core computes the map (LensCamera.cropMap, render/lens_crop.hpp).
 */
export function cropImageMapped(image, map, outW, outH = outW, out = new Float32Array(outW * outH * 3), border = 'zero') {
  if (border !== 'zero' && border !== 'replicate') throw new Error(`cropImageMapped: border '${border}' (zero or replicate)`);
  const replicate = border === 'replicate';
  const { width: W, height: H, data } = image;
  const ch = image.channels ?? 4;
  if (ch !== 3 && ch !== 4) throw new Error(`cropImageMapped: ${ch} channels (3 = RGB or 4 = RGBA expected)`);
  if (data.length < W * H * ch) throw new Error(`cropImageMapped: ${data.length} bytes for a ${W}x${H}x${ch} image`);
  if (map.length !== 2 * outW * outH) throw new Error(`cropImageMapped: a map of ${map.length} numbers for ${outW}x${outH}`);
  if (out.length !== outW * outH * 3) throw new Error(`cropImageMapped: output of ${out.length} floats for ${outW}x${outH}x3`);
  for (let p = 0, o = 0; p < outW * outH; ++p, o += 3) {
    const x = map[2 * p];
    const y = map[2 * p + 1];
    if (Number.isFinite(x) && Number.isFinite(y)) sampleBilinear(data, W, H, ch, x, y, replicate, out, o);
    else out[o] = out[o + 1] = out[o + 2] = 0;
  }
  return out;
}

/** Intersection over union of two axis-aligned boxes {cx, cy, w, h}. */
export function iou(a, b) {
  const ix = Math.min(a.cx + a.w / 2, b.cx + b.w / 2) - Math.max(a.cx - a.w / 2, b.cx - b.w / 2);
  const iy = Math.min(a.cy + a.h / 2, b.cy + b.h / 2) - Math.max(a.cy - a.h / 2, b.cy - b.h / 2);
  if (ix <= 0 || iy <= 0) return 0;
  const inter = ix * iy;
  return inter / (a.w * a.h + b.w * b.h - inter);
}
