// video_source.mjs — frames of a video file, decoded by the browser's own <video> element and
// read back through a canvas, one at a time (streamed: no frame is kept after it is handed on).
//
// Decoding is sequential: the video plays and pauses on every presented frame
// (requestVideoFrameCallback), so the decoder never restarts from a keyframe; a frame the
// player skipped is fetched by a seek. Frames are scaled to the processing size on the canvas.

export class InputError extends Error {
  constructor(kind, message) { super(message); this.name = 'InputError'; this.kind = kind; }
}

/// Limits of the app (stated in the error messages).
export const LIMITS = { maxSide: 4096, minFrames: 8, minSeconds: 0.25 };

const MEDIA_ERRORS = { 1: 'aborted', 2: 'network error', 3: 'decoding failed (corrupt or truncated file?)', 4: 'format or codec not supported by this browser' };

function once(target, okEvents, errEvents, timeoutMs, what) {
  return new Promise((resolve, reject) => {
    const off = () => { for (const e of okEvents) target.removeEventListener(e, ok); for (const e of errEvents) target.removeEventListener(e, bad); clearTimeout(timer); };
    const ok = (ev) => { off(); resolve(ev); };
    const bad = (ev) => { off(); reject(ev); };
    for (const e of okEvents) target.addEventListener(e, ok);
    for (const e of errEvents) target.addEventListener(e, bad);
    const timer = setTimeout(() => { off(); reject(new InputError('timeout', `${what}: the browser gave no answer within ${timeoutMs / 1000} s`)); }, timeoutMs);
  });
}

function mediaError(video, name) {
  const e = video.error;
  const why = e ? (MEDIA_ERRORS[e.code] || `error ${e.code}`) + (e.message ? ` — ${e.message}` : '') : 'unknown error';
  return new InputError('video', `Cannot read the video "${name}": ${why}. Supported here: whatever this browser plays (MP4/H.264, WebM/VP8/VP9/AV1 in Chromium).`);
}

/// Loads `url` into `video` and checks it: decodable, not huge, not too short.
/// Returns { width, height, duration }.
export async function openVideo(video, url, name = 'video', timeoutMs = 20000) {
  video.pause();
  video.muted = true;
  video.playsInline = true;
  video.preload = 'auto';
  const loaded = once(video, ['loadeddata'], ['error'], timeoutMs, `Loading "${name}"`);
  video.src = url;
  video.load();
  try { await loaded; } catch (e) { if (e instanceof InputError) throw e; throw mediaError(video, name); }
  const width = video.videoWidth, height = video.videoHeight, duration = video.duration;
  if (!width || !height) throw new InputError('video', `"${name}" has no video track (audio only?).`);
  if (Math.max(width, height) > LIMITS.maxSide) {
    throw new InputError('resolution', `"${name}" is ${width}×${height}: above this app's limit of ${LIMITS.maxSide} px on the long side. Downscale it first (e.g. ffmpeg -i IN -vf scale=1920:-2 OUT.mp4).`);
  }
  if (!Number.isFinite(duration) || duration < LIMITS.minSeconds) {
    throw new InputError('short', `"${name}" is too short (${Number.isFinite(duration) ? duration.toFixed(2) + ' s' : 'unknown length'}): at least ${LIMITS.minFrames} frames are needed.`);
  }
  return { width, height, duration };
}

function nextPresented(video, draw, timeoutMs = 15000) {
  return new Promise((resolve, reject) => {
    let done = false;
    const timer = setTimeout(() => {
      if (done) return;
      done = true;
      video.pause();
      reject(new InputError('video', `The video stopped decoding at ${video.currentTime.toFixed(2)} s (no new frame for ${timeoutMs / 1000} s).`));
    }, timeoutMs);
    const onEnd = () => { if (!done) { done = true; clearTimeout(timer); video.removeEventListener('error', onErr); resolve(null); } };
    const onErr = () => { if (!done) { done = true; clearTimeout(timer); video.removeEventListener('ended', onEnd); reject(mediaError(video, 'video')); } };
    video.addEventListener('ended', onEnd, { once: true });
    video.addEventListener('error', onErr, { once: true });
    video.requestVideoFrameCallback((now, md) => {
      if (done) return;
      done = true;
      clearTimeout(timer);
      const px = draw();           // inside the callback: exactly the presented frame
      video.pause();
      video.removeEventListener('ended', onEnd);
      video.removeEventListener('error', onErr);
      resolve({ mediaTime: md.mediaTime, presentedFrames: md.presentedFrames, px });
    });
    const p = video.play();
    if (p && p.catch) p.catch((e) => { if (!done) { done = true; clearTimeout(timer); reject(new InputError('video', `The browser refused to play the video: ${e.message}`)); } });
  });
}

async function seek(video, t) {
  const s = once(video, ['seeked'], ['error'], 10000, 'Seeking');
  video.currentTime = t;
  try { await s; } catch (e) { if (e instanceof InputError) throw e; throw mediaError(video, 'video'); }
}

const COMMON_FPS = [23.976, 24, 25, 29.97, 30, 48, 50, 59.94, 60, 90, 100, 119.88, 120];

/// Frame rate from the presentation times of the first frames (the smallest step between
/// consecutive presented frames; snapped to a common rate within 1 %) and the presentation
/// time of the first frame. Leaves the video at 0.
export async function estimateFps(video, frames = 12) {
  await seek(video, 0);
  const times = [];
  for (let i = 0; i < frames; i++) {
    const f = await nextPresented(video, () => null);
    if (!f) break;
    times.push(f.mediaTime);
  }
  await seek(video, 0);
  const deltas = [];
  for (let i = 1; i < times.length; i++) { const d = times[i] - times[i - 1]; if (d > 1e-4) deltas.push(d); }
  if (!deltas.length) return { fps: null, base: 0, presented: times.length };
  // The frame step: the mean of the steps within 1.5x the smallest (skipped frames left out;
  // container timestamps are often rounded to milliseconds).
  const dmin = Math.min(...deltas);
  const near = deltas.filter((d) => d < 1.5 * dmin);
  const step = near.reduce((a, b) => a + b, 0) / near.length;
  let fps = Math.round(1000 / step) / 1000;
  let best = null;
  for (const c of COMMON_FPS) if (Math.abs(fps / c - 1) < 0.015 && (best === null || Math.abs(fps - c) < Math.abs(fps - best))) best = c;
  if (best !== null) fps = best;
  // Frames lie on the grid base + k / fps; playing from a paused frame 0 presents frame 1 first.
  const base = times[0] - Math.round(times[0] * fps) / fps;
  return { fps, base, presented: times.length };
}

/// The processing size: the video scaled so that its long side is at most maxSide.
export function processingSize(width, height, maxSide) {
  const s = Math.min(1, maxSide / Math.max(width, height));
  return { width: Math.max(2, Math.round(width * s)), height: Math.max(2, Math.round(height * s)), scale: s };
}

/// A function that captures the video's current picture (synchronously: call it inside the
/// requestVideoFrameCallback) and resolves to its RGBA pixels at width x height.
///
/// Drawing the <video> element into a canvas makes Chromium convert and cache every 1080p frame
/// (about 570 MB more in the renderer on a 1080p clip, measured); instead the picture is taken as
/// a WebCodecs VideoFrame, copied as RGBA into one reused buffer, and only that buffer is drawn
/// (scaled) into the output canvas (about 60 MB). Where VideoFrame is missing, or its picture
/// is not the element's (a rotated video), the element is drawn directly.
export function frameGrabber(video, width, height) {
  const out = new OffscreenCanvas(width, height).getContext('2d', { willReadFrequently: true });
  let full = null, fullCtx = null, fullImage = null;
  let direct = typeof VideoFrame === 'undefined';
  let chain = Promise.resolve();
  const viaFrame = async (frame) => {
    try {
      const W = frame.visibleRect.width, H = frame.visibleRect.height;
      if (!full || full.width !== W || full.height !== H) {
        full = new OffscreenCanvas(W, H);
        fullCtx = full.getContext('2d');
        fullImage = new ImageData(W, H);
      }
      await frame.copyTo(fullImage.data, { format: 'RGBA' });
      fullCtx.putImageData(fullImage, 0, 0);
      out.drawImage(full, 0, 0, width, height);
      return out.getImageData(0, 0, width, height).data;
    } finally {
      frame.close();
    }
  };
  const viaElement = () => { out.drawImage(video, 0, 0, width, height); return out.getImageData(0, 0, width, height).data; };
  return () => {
    if (!direct) {
      let frame = null;
      try {
        frame = new VideoFrame(video);
        if (frame.visibleRect.width !== video.videoWidth || frame.visibleRect.height !== video.videoHeight) throw new Error('rotated');
      } catch {
        if (frame) frame.close();
        direct = true;
      }
      if (!direct) {
        const p = chain.then(() => viaFrame(frame)).catch(() => { direct = true; return null; });
        chain = p;
        return p.then((px) => px || viaElement());
      }
    }
    const p = chain.then(viaElement);
    chain = p.catch(() => null);
    return p;
  };
}

/// Async iterable of { index, rgba } at the processing size, in order, every frame once.
/// `wait()` (optional) is awaited before decoding each next frame (back-pressure).
export function videoFrames(video, { fps, base = 0, width, height, maxFrames = Infinity, signal, wait }) {
  const draw = frameGrabber(video, width, height);
  return {
    async *[Symbol.asyncIterator]() {
      await seek(video, 0);
      let expected = 0;
      // Frame 0: the picture shown after the seek to 0.
      yield { index: 0, rgba: await draw() };
      expected = 1;
      while (expected < maxFrames) {
        if (signal && signal.aborted) return;
        if (wait) await wait();
        if (signal && signal.aborted) return;
        const f = await nextPresented(video, draw);
        if (!f) {
          // Ended: the player may end before presenting the last frame(s); they are fetched by
          // seeking while they lie inside the duration.
          for (; expected < maxFrames && base + (expected + 0.25) / fps < video.duration; expected++) {
            await seek(video, base + (expected + 0.25) / fps);
            yield { index: expected, rgba: await draw() };
            if (wait) await wait();
          }
          return;
        }
        const idx = Math.round((f.mediaTime - base) * fps);
        if (idx < expected) continue;                      // the same frame again
        // Frames the player skipped: fetched one by one by seeking, in order.
        for (; expected < idx && expected < maxFrames; expected++) {
          await seek(video, base + (expected + 0.25) / fps);
          yield { index: expected, rgba: await draw() };
          if (wait) await wait();
        }
        if (expected >= maxFrames) return;
        if (expected === idx) {
          // Back to where playback was (the seeks moved it).
          if (Math.abs(video.currentTime - f.mediaTime) > 0.5 / fps) await seek(video, f.mediaTime);
          yield { index: expected, rgba: await f.px };
          expected++;
        }
      }
    },
  };
}

