// The choice of the hand networks' backend (web/src/perception/execution_provider.mjs) against
// stand-in onnxruntime namespaces and WebGPU adapters: each rule that keeps WebAssembly, and the
// two ways WebGPU is taken. The real backends in a browser: tests/browser/webgpu.test.mjs.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { chooseProvider, outputDisagreement, AGREE_REL } from '../../web/src/perception/execution_provider.mjs';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/// A stand-in onnxruntime namespace: every session answers `scale × sum(input)` after `ms`.
function fakeOrt({ ms, scale = 1, failCreate = false }) {
  const created = [];
  const released = [];
  class Tensor { constructor(type, data, dims) { Object.assign(this, { type, data, dims }); } }
  const InferenceSession = {
    async create(bytes, options) {
      if (failCreate) throw new Error('no kernel for Op X');
      created.push(options);
      const session = {
        inputNames: ['x'], outputNames: ['a', 'b'],
        async run(feeds) {
          await sleep(ms);
          let s = 0; for (const v of feeds.x.data) s += v;
          return { a: { data: Float32Array.of(s * scale, 1) }, b: { data: Float32Array.of(bytes.length) } };
        },
        async release() { released.push(session); },
      };
      return session;
    },
  };
  return { Tensor, InferenceSession, created, released };
}
const gpuWith = (info) => ({ async requestAdapter() { return info ? { info } : null; } });
const models = { palm: new Uint8Array(3), landmark: new Uint8Array(5) };
const real = { vendor: 'acme', architecture: 'rdna3' };

test('outputDisagreement: relative to the largest magnitude; sizes or non-finite values disagree', () => {
  assert.ok(Math.abs(outputDisagreement([10, 1], [10, 1.01]) - 0.001) < 1e-12);
  assert.equal(outputDisagreement([0, 0], [0, 0]), 0);
  assert.equal(outputDisagreement([1], [1, 2]), Infinity);
  assert.equal(outputDisagreement([1], [NaN]), Infinity);
});

test('WebAssembly is kept without WebGPU, without an adapter, on a software adapter, or when asked', async () => {
  const ort = fakeOrt({ ms: 1 });
  let loaded = 0;
  const loadWebgpu = async () => { ++loaded; return fakeOrt({ ms: 1 }); };
  const cases = [
    [{ gpu: null }, /no WebGPU/],
    [{ gpu: gpuWith(null) }, /no adapter/],
    [{ gpu: gpuWith({ vendor: 'google', architecture: 'swiftshader' }) }, /software renderer \(google swiftshader\)/],
    [{ gpu: gpuWith({ ...real, isFallbackAdapter: true }) }, /software renderer/],
    [{ gpu: gpuWith(real), preference: 'wasm' }, /WebAssembly was asked for/],
  ];
  for (const [o, why] of cases) {
    const r = await chooseProvider({ ort, loadWebgpu, models, ...o });
    assert.equal(r.provider, 'wasm');
    assert.equal(r.ort, ort);
    assert.match(r.why, why);
  }
  assert.equal(loaded, 0, 'the WebGPU build is loaded only where it may be used');
});

test("'auto' takes WebGPU only when it agrees and is faster", async () => {
  const ort = fakeOrt({ ms: 30 });
  const fast = fakeOrt({ ms: 2 });
  const r = await chooseProvider({ ort, loadWebgpu: async () => fast, models, gpu: gpuWith(real) });
  assert.equal(r.provider, 'webgpu', r.why);
  assert.equal(r.ort, fast);
  assert.deepEqual(r.sessionOptions.executionProviders, ['webgpu']);
  assert.ok(r.ms.webgpu < r.ms.wasm && r.disagreement === 0, JSON.stringify(r));
  assert.match(r.why, /faster here/);
  // the winner's sessions are handed on with the hand tracker's session options, the loser's released
  assert.equal(ort.released.length, 2);
  assert.equal(fast.released.length, 0);
  assert.deepEqual(r.sessions.palmSession.inputNames, ['x']);
  assert.equal(fast.created[0].graphOptimizationLevel, 'all');
  assert.deepEqual(fast.created[0].executionProviders, ['webgpu']);

  const slow = await chooseProvider({ ort: fakeOrt({ ms: 2 }), loadWebgpu: async () => fakeOrt({ ms: 30 }), models, gpu: gpuWith(real) });
  assert.equal(slow.provider, 'wasm');
  assert.match(slow.why, /not faster here/);
  assert.ok(slow.sessions && slow.sessions.palmSession, 'the WebAssembly probe\'s sessions are handed on');

  const off = await chooseProvider({ ort, loadWebgpu: async () => fakeOrt({ ms: 2, scale: 1 + 10 * AGREE_REL }), models, gpu: gpuWith(real) });
  assert.equal(off.provider, 'wasm');
  assert.match(off.why, /outputs differ/);

  const broken = await chooseProvider({ ort, loadWebgpu: async () => fakeOrt({ ms: 2, failCreate: true }), models, gpu: gpuWith(real) });
  assert.equal(broken.provider, 'wasm');
  assert.match(broken.why, /failed on WebGPU \(no kernel for Op X\)/);

  const unloadable = await chooseProvider({ ort, loadWebgpu: async () => { throw new Error('404'); }, models, gpu: gpuWith(real) });
  assert.equal(unloadable.provider, 'wasm');
  assert.match(unloadable.why, /could not be loaded \(404\)/);
});

test("asked for WebGPU, it runs wherever it agrees, slower or not; an unknown choice is refused", async () => {
  const r = await chooseProvider({ preference: 'webgpu', ort: fakeOrt({ ms: 1 }), loadWebgpu: async () => fakeOrt({ ms: 10 }), models, gpu: gpuWith({ vendor: 'google', architecture: 'swiftshader' }) });
  assert.equal(r.provider, 'webgpu', r.why);
  assert.match(r.why, /was asked for; its outputs agree/);
  const off = await chooseProvider({ preference: 'webgpu', ort: fakeOrt({ ms: 1 }), loadWebgpu: async () => fakeOrt({ ms: 1, scale: 2 }), models, gpu: gpuWith(real) });
  assert.equal(off.provider, 'wasm');
  await assert.rejects(chooseProvider({ preference: 'cuda', ort: fakeOrt({ ms: 1 }), models }), /unknown network backend "cuda"/);
});
