// The WASM core (wasm/bindings.cpp) under node, against the independent numpy references:
// metrics vs tests/ref/metrics_np.py, npz written here read by numpy and vice versa, and errors
// surfacing as readable exceptions. Usage: node test_bindings.mjs path/to/hawor_core.mjs python3
import { createRequire } from 'node:module';
import { execFileSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const [modulePath, python] = process.argv.slice(2);
const here = path.dirname(fileURLToPath(import.meta.url));
// Emscripten's EXPORT_ES6 output reads require/__dirname in node (DESIGN §9).
globalThis.require = createRequire(import.meta.url);
globalThis.__dirname = path.dirname(path.resolve(modulePath));
const { default: createHaworCore } = await import(pathToFileURL(path.resolve(modulePath)).href);
// In node the module must be told where its .wasm is (its default is a file: URL).
const core = await createHaworCore({ locateFile: (f) => path.join(globalThis.__dirname, f) });

let passed = 0, failed = 0;
function check(name, ok, detail = '') {
  if (ok) passed++; else { failed++; console.log('FAIL:', name, detail); }
}
function close(a, b, rtol = 1e-9) {
  return Math.abs(a - b) <= rtol * Math.max(Math.abs(b), 1e-300) || Math.abs(a - b) <= 1e-12;
}
// Deterministic pseudo-random numbers (mulberry32 + Box-Muller).
let seed = 12345;
function rand() {
  seed |= 0; seed = (seed + 0x6d2b79f5) | 0;
  let t = Math.imul(seed ^ (seed >>> 15), 1 | seed);
  t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
}
function randn() { return Math.sqrt(-2 * Math.log(rand() + 1e-300)) * Math.cos(2 * Math.PI * rand()); }
function randArray(n, scale = 1, offset = 0) {
  const a = new Float64Array(n); for (let i = 0; i < n; i++) a[i] = offset + scale * randn(); return a;
}
function pythonJson(script, input) {
  const out = execFileSync(python, ['-c', script], {
    input: JSON.stringify(input), env: { ...process.env, PYTHONPATH: path.join(here, '..', 'ref') },
    maxBuffer: 1 << 28,
  });
  return JSON.parse(out.toString());
}

// --- metrics ------------------------------------------------------------------------------------
const T = 230, J = 21;
const gtPos = new Float64Array(T * 3);
for (let t = 0; t < T; t++) { gtPos[3 * t] = Math.sin(t / 20); gtPos[3 * t + 1] = 0.1 * t / T; gtPos[3 * t + 2] = t / 50; }
const estPos = gtPos.map((v, i) => 0.7 * v + 0.01 * randn() + (i % 3 === 0 ? 0.3 : 0));
const gtWorld = randArray(T * J * 3, 0.05, 0.2), gtCam = randArray(T * J * 3, 0.05, 0.4);
const estWorld = gtWorld.map((v) => v + 0.01 * randn() + 0.05), estCam = gtCam.map((v) => v + 0.008 * randn());
const valid = new Uint8Array(T).map(() => (rand() > 0.15 ? 1 : 0));
const cam = core.evaluateCameras(gtPos, estPos);
const hands = core.evaluateHands(gtWorld, estWorld, gtCam, estCam, T, valid, 30);
const ref = pythonJson(`
import json, sys, numpy as np, metrics_np as M
d = json.load(sys.stdin)
g = np.array(d['gtPos']).reshape(-1, 3); e = np.array(d['estPos']).reshape(-1, 3)
gw = np.array(d['gtWorld']).reshape(-1, 21, 3); ew = np.array(d['estWorld']).reshape(-1, 21, 3)
gc = np.array(d['gtCam']).reshape(-1, 21, 3); ec = np.array(d['estCam']).reshape(-1, 21, 3)
v = np.array(d['valid']).astype(bool)
ate, scale = M.ate(g, e)
print(json.dumps(dict(ate=ate, ate_s=M.ate_s(g, e), scale=scale, pa_mpjpe=M.pa_mpjpe(gc, ec, v),
    auc=M.auc(gc, ec, v), w_mpjpe=M.w_mpjpe(gw, ew, v), wa_mpjpe=M.wa_mpjpe(gw, ew, v),
    rte=M.rte(gw, ew, v), accel=M.accel(gw, ew, v, 30.0), n=int(v.sum()))))
`, { gtPos: [...gtPos], estPos: [...estPos], gtWorld: [...gtWorld], estWorld: [...estWorld],
     gtCam: [...gtCam], estCam: [...estCam], valid: [...valid] });
for (const k of ['ate', 'ate_s', 'scale']) check(`camera ${k}`, close(cam[k], ref[k]), `${cam[k]} vs ${ref[k]}`);
for (const k of ['pa_mpjpe', 'auc', 'w_mpjpe', 'wa_mpjpe', 'rte', 'accel', 'n'])
  check(`hands ${k}`, close(hands[k], ref[k]), `${hands[k]} vs ${ref[k]}`);

// --- npz both ways ------------------------------------------------------------------------------
for (const compressed of [false, true]) {
  const bytes = core.writeNpz({
    a: { shape: [2, 3], data: new Float64Array([1, 2, 3, 4, 5, 6.5]) },
    b: { shape: [4], data: new Float32Array([0.5, -1, 2, 1e-3]) },
    c: { shape: [3], data: new Uint8Array([0, 1, 255]) },
  }, compressed);
  const back = pythonJson(`
import json, sys, io, numpy as np
z = np.load(io.BytesIO(bytes(json.load(sys.stdin))))
print(json.dumps({k: dict(shape=list(z[k].shape), dtype=z[k].dtype.str, data=z[k].ravel().tolist()) for k in z.files}))
`, [...bytes]);
  check(`npz ${compressed} a`, back.a.dtype === '<f8' && back.a.shape.join() === '2,3' && back.a.data.join() === '1,2,3,4,5,6.5');
  check(`npz ${compressed} b`, back.b.dtype === '<f4' && back.b.data[3] === Math.fround(1e-3));
  check(`npz ${compressed} c`, back.c.dtype === '|u1' && back.c.data.join() === '0,1,255');
}
const fromNumpy = pythonJson(`
import json, io, numpy as np
buf = io.BytesIO(); np.savez_compressed(buf, x=np.arange(12, dtype=np.int16).reshape(3, 4), y=np.asfortranarray(np.eye(3)))
print(json.dumps(list(buf.getvalue())))
`, null);
const z = core.readNpz(new Uint8Array(fromNumpy), 'numpy.npz');
check('readNpz x', z.x.shape.join() === '3,4' && z.x.data[11] === 11 && z.x.dtype === '<i2');
check('readNpz y', z.y.data[0] === 1 && z.y.data[1] === 0 && z.y.data[4] === 1);

// --- errors -------------------------------------------------------------------------------------
function message(fn) {
  try { fn(); } catch (e) { return typeof e === 'number' ? core.errorMessage(e) : String(e.message || e); }
  return null;
}
const m1 = message(() => core.readNpz(new Uint8Array([80, 75, 3, 4, 1, 2, 3]), 'broken.npz'));
check('corrupt npz throws a message', m1 !== null && m1.includes('broken.npz'), m1);
const m2 = message(() => core.evaluateCameras(new Float64Array(7), new Float64Array(7)));
check('bad length throws a message', m2 !== null && m2.includes('multiple of 3'), m2);
check('module still usable after errors', close(core.evaluateCameras(gtPos, estPos).ate, ref.ate));

console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
