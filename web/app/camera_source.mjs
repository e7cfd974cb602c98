// camera_source.mjs — a camera's frames for live mode (getUserMedia): the device list, the camera
// opened into the page's <video>, and its frames handed over one at a time, each only when the
// consumer asks for one (drop, never queue): a frame presented while none is asked for is
// dropped (counted), and the newest such frame waits for the next ask.
import { InputError } from './video_source.mjs';

/** The format asked of the camera (the browser picks the nearest it has). */
export const CAMERA_CONSTRAINTS = Object.freeze({ width: { ideal: 960 }, height: { ideal: 540 }, frameRate: { ideal: 30 } });

/// Fills `select` with the cameras ('' first: the default one); their names appear once the
/// browser allowed the camera. Keeps the choice where it is still there.
export async function listCameras(select) {
  const md = navigator.mediaDevices;
  if (!md || !md.enumerateDevices) return;
  let cams;
  try { cams = (await md.enumerateDevices()).filter((d) => d.kind === 'videoinput' && d.deviceId); } catch { return; }
  const keep = select.value;
  select.textContent = '';
  select.append(new Option('default camera', ''));
  cams.forEach((d, i) => select.append(new Option(d.label || `camera ${i + 1}`, d.deviceId)));
  if ([...select.options].some((o) => o.value === keep)) select.value = keep;
}

/// A getUserMedia failure as an InputError for the page's message.
export function cameraError(e, deviceId) {
  const why = e && e.message ? ` (${e.message})` : '';
  switch (e && e.name) {
    case 'NotAllowedError': case 'SecurityError':
      return new InputError('webcam-denied', `the camera was not allowed for this page${why}. Allow it (the camera icon in the address bar, or the browser's site settings) and press Camera again.`);
    case 'NotFoundError': case 'OverconstrainedError':
      return new InputError('webcam-none', deviceId ? `the chosen camera is not available${why}; pick another one, or "default camera".` : `no camera was found${why}.`);
    case 'NotReadableError': case 'AbortError': case 'TrackStartError':
      return new InputError('webcam-busy', `the camera could not be started${why}: another application or tab is probably using it. Close that, then press Camera again.`);
    default:
      return new InputError('webcam', `the camera could not be opened: ${(e && e.message) || e}`);
  }
}

/// Opens a camera ('' : the default one). Returns { stream, track }; throws an InputError.
export async function openCamera(deviceId = '') {
  const md = navigator.mediaDevices;
  if (!md || !md.getUserMedia) {
    throw new InputError('webcam', window.isSecureContext ? 'this browser gives the page no camera (navigator.mediaDevices is missing).'
      : 'a camera needs a secure page: open the app over https, or at http://127.0.0.1 or http://localhost.');
  }
  let stream;
  try {
    stream = await md.getUserMedia({ audio: false, video: { ...CAMERA_CONSTRAINTS, ...(deviceId ? { deviceId: { exact: deviceId } } : {}) } });
  } catch (e) {
    throw cameraError(e, deviceId);
  }
  const track = stream.getVideoTracks()[0];
  if (!track) { for (const t of stream.getTracks()) t.stop(); throw new InputError('webcam-none', 'the camera gave no video track.'); }
  return { stream, track };
}

/// Plays `stream` in `video`; resolves to { width, height, fps, label } once its picture plays.
export function playCamera(video, stream, track, timeoutMs = 15000) {
  video.removeAttribute('src');
  video.srcObject = stream;
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new InputError('webcam', `the camera sent no picture within ${timeoutMs / 1000} s.`)), timeoutMs);
    const go = () => video.play().then(() => {
      clearTimeout(timer);
      const s = track.getSettings();
      resolve({ width: video.videoWidth || s.width, height: video.videoHeight || s.height,
        fps: s.frameRate > 0 ? Math.round(s.frameRate * 1000) / 1000 : null, label: track.label || '' });
    }, (e) => { clearTimeout(timer); reject(new InputError('webcam', `the browser refused to play the camera: ${e.message}`)); });
    if (video.readyState >= 1) go(); else video.addEventListener('loadedmetadata', go, { once: true });
  });
}

/// Stops the camera and takes it out of `video`.
export function closeCamera(video, stream) {
  if (!stream) return;
  for (const t of stream.getTracks()) t.stop();
  if (video.srcObject === stream) video.srcObject = null;
}

/**
 * The frames of the camera playing in `video`, at width x height (RGBA, drawn scaled into a
 * canvas), handed to `send({ index, rgba: Uint8ClampedArray, time })` one per ask(): at once when
 * a frame not handed over was presented since the last one, else on the next presented frame.
 * `time` is the frame's capture time (requestVideoFrameCallback's captureTime, performance.now()'s
 * clock) where the browser gives it, else the time it was composited (`clock` says which).
 * captured counts the camera's frames presented from the first one handed over on; dropped =
 * captured - sent.
 */
export class CameraFrames {
  constructor(video, width, height, send) {
    this.video = video;
    this.width = width;
    this.height = height;
    this.sendFn = send;
    this.ctx = new OffscreenCanvas(width, height).getContext('2d', { willReadFrequently: true });
    this.asks = 0;
    this.sent = 0;
    this.first = null;       // presentedFrames of the first frame handed over
    this.last = null;        // the latest presentedFrames since
    this.pending = null;     // the newest presented frame not handed over
    this.clock = null;
    this.stopped = false;
    this.video.requestVideoFrameCallback((now, md) => this.presented(now, md));
  }

  get captured() { return this.first === null ? 0 : this.last - this.first + 1; }
  get dropped() { return Math.max(0, this.captured - this.sent); }

  /// The consumer is ready for one more frame.
  ask() {
    if (this.stopped) return;
    this.asks++;
    if (this.pending) this.hand(this.pending);
  }

  stop() { this.stopped = true; this.pending = null; }

  presented(now, md) {
    if (this.stopped) return;
    const cap = Number.isFinite(md.captureTime) && md.captureTime > 0 && md.captureTime <= performance.now();
    this.clock ||= cap ? 'captureTime' : 'presentationTime';
    const f = { presented: md.presentedFrames, time: cap ? md.captureTime : md.presentationTime };
    if (this.asks > 0) this.hand(f); else this.pending = f;
    if (this.first !== null) this.last = Math.max(this.last, f.presented);
    this.video.requestVideoFrameCallback((t, m) => this.presented(t, m));
  }

  hand(f) {
    this.pending = null;
    this.asks--;
    if (this.first === null) this.first = this.last = f.presented;
    this.ctx.drawImage(this.video, 0, 0, this.width, this.height);
    const rgba = this.ctx.getImageData(0, 0, this.width, this.height).data;
    this.sendFn({ index: this.sent++, rgba, time: f.time });
  }
}
