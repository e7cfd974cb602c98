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
  // `n` pixels from it (pixel k covers [k - 0.5, k + 0.5]; outside the image: weight 0)
  const taps = (c, size, count, N) => {
    const step = size / count;
    const half = Math.max(0.5, (footprint * step) / 2);
    const n = Math.ceil(2 * half) + 1;
    const first = new Int32Array(count);
    const weights = new Float32Array(count * n);
    for (let i = 0; i < count; ++i) {
      const mid = c - size / 2 + (i + 0.5) * step;
      const a = mid - half;
      const b = mid + half;
      const k0 = Math.round(a);
      first[i] = k0;
      for (let q = 0; q < n; ++q) {
        const k = k0 + q;
        const overlap = Math.min(b, k + 0.5) - Math.max(a, k - 0.5);
        weights[i * n + q] = k >= 0 && k < N && overlap > 0 ? overlap / (b - a) : 0;
      }
    }
    return { first, weights, n };
  };
  const tx = taps(roi.cx, roi.w, outW, W);
  const ty = taps(roi.cy, roi.h, outH, H);
  const k = 1 / 255;
  const acc = new Float32Array(outW * 3);
  for (let j = 0; j < outH; ++j) {
    acc.fill(0);
    for (let q = 0; q < ty.n; ++q) {
      const wy = ty.weights[j * ty.n + q];
      if (wy === 0) continue;
      const base = (ty.first[j] + q) * W;
      for (let i = 0; i < outW; ++i) {
        let R = 0;
        let G = 0;
        let B = 0;
        const x0 = tx.first[i];
        for (let p = 0; p < tx.n; ++p) {
          const wgt = tx.weights[i * tx.n + p];
          if (wgt === 0) continue;
          const o = (base + x0 + p) * ch;
          R += wgt * data[o];
          G += wgt * data[o + 1];
          B += wgt * data[o + 2];
        }
        acc[3 * i] += wy * R;
        acc[3 * i + 1] += wy * G;
        acc[3 * i + 2] += wy * B;
      }
    }
    const o = j * outW * 3;
    for (let i = 0; i < 3 * outW; ++i) out[o + i] = acc[i] * k;
  }
  return out;
}
