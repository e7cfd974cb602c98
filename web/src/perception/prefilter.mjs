// prefilter.mjs: the palm detector's view of the whole frame, resampled with a box prefilter.
//
// The detector sees the frame letterboxed into 192 x 192: a 1080p frame is shrunk 10 times.
// Sampling it at single points (bilinear, geometry.mjs's cropImage) aliases everything finer than
// the sample spacing into the input: sensor noise keeps its full amplitude (at noise strength 25
// the best palm score near a hand fell from a median of 0.6-0.7 to 0.1). Averaging each sample
// over a box of `footprint` times the sample spacing (at least one source pixel, where it is
// exactly bilinear interpolation) removes that noise; a full footprint (an area average) also
// softens the edges the detector was trained on (its scores on the clean clip fell from 0.65 to
// 0.56), half a spacing keeps them (docs/benchmarks.md, real-video robustness).

/**
 * Samples an outW x outH crop of an axis-aligned ROI {cx, cy, w, h} (rotation 0) into NHWC float
 * RGB in 0..1: output pixel (i, j) is the mean of the image over a box centred on the point
 * cropImage would sample, max(1, footprint * w / outW) source pixels wide (and alike in y),
 * pixels weighted by their overlap with it. Outside the image reads black (cropImage's 'zero'
 * border: the palm letterbox). Pixel centres at integer coordinates (docs/design.md §2).
 * @param image {width, height, data, channels: 3 | 4}
 */
export function cropBoxFiltered(image, roi, outW, outH = outW, out = new Float32Array(outW * outH * 3), footprint = 0.5) {
  if (roi.rotation) throw new Error('cropBoxFiltered: axis-aligned ROIs only');
  const { width: W, height: H, data } = image;
  const ch = image.channels ?? 4;
  if (ch !== 3 && ch !== 4) throw new Error(`cropBoxFiltered: ${ch} channels (3 = RGB or 4 = RGBA expected)`);
  if (data.length < W * H * ch) throw new Error(`cropBoxFiltered: ${data.length} bytes for a ${W}x${H}x${ch} image`);
  if (out.length !== outW * outH * 3) throw new Error(`cropBoxFiltered: output of ${out.length} floats for ${outW}x${outH}x3`);
  if (!(footprint >= 0)) throw new Error(`cropBoxFiltered: footprint ${footprint}`);
  // the taps of one axis: for output index i, the first source pixel and the weights of the
  // pixels its box overlaps (pixel k covers [k - 0.5, k + 0.5]; outside the image: weight 0)
  const taps = (c, size, n, N) => {
    const first = new Int32Array(n);
    const weights = [];
    const step = size / n;
    const half = Math.max(0.5, (footprint * step) / 2);
    for (let i = 0; i < n; ++i) {
      const mid = c - size / 2 + (i + 0.5) * step;
      const a = mid - half;
      const b = mid + half;
      const k0 = Math.round(a);
      const k1 = Math.round(b);
      const w = [];
      for (let k = k0; k <= k1; ++k) {
        const overlap = Math.min(b, k + 0.5) - Math.max(a, k - 0.5);
        w.push(k >= 0 && k < N && overlap > 0 ? overlap / (b - a) : 0);
      }
      first[i] = k0;
      weights.push(Float64Array.from(w));
    }
    return { first, weights };
  };
  const tx = taps(roi.cx, roi.w, outW, W);
  const ty = taps(roi.cy, roi.h, outH, H);
  // rows filtered horizontally once each (a row serves every output row whose box covers it)
  const rows = new Map();
  const filteredRow = (y) => {
    let r = rows.get(y);
    if (r) return r;
    r = new Float64Array(outW * 3);
    const base = y * W;
    for (let i = 0; i < outW; ++i) {
      const wx = tx.weights[i];
      const x0 = tx.first[i];
      let R = 0;
      let G = 0;
      let B = 0;
      for (let p = 0; p < wx.length; ++p) {
        const wgt = wx[p];
        if (wgt === 0) continue;
        const q = (base + x0 + p) * ch;
        R += wgt * data[q];
        G += wgt * data[q + 1];
        B += wgt * data[q + 2];
      }
      r[3 * i] = R;
      r[3 * i + 1] = G;
      r[3 * i + 2] = B;
    }
    rows.set(y, r);
    return r;
  };
  const k = 1 / 255;
  const acc = new Float64Array(outW * 3);
  for (let j = 0; j < outH; ++j) {
    acc.fill(0);
    const wy = ty.weights[j];
    for (let q = 0; q < wy.length; ++q) {
      if (wy[q] === 0) continue;
      const r = filteredRow(ty.first[j] + q);
      for (let i = 0; i < 3 * outW; ++i) acc[i] += wy[q] * r[i];
    }
    const o = j * outW * 3;
    for (let i = 0; i < 3 * outW; ++i) out[o + i] = acc[i] * k;
  }
  return out;
}
