// parseDepthConfig: a valid config is normalised; every bad field is refused with its name.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { parseDepthConfig } from '../../web/src/depth_model.mjs';

const valid = () => ({
  format: 'hawor-depth-model',
  version: 1,
  input: { width: 64, height: 48, layout: 'NCHW' },
  normalize: { scale: 1 / 255, mean: [0.485, 0.456, 0.406], std: [0.229, 0.224, 0.225] },
  output: { kind: 'metric_depth' },
});

/** A valid config with `path` (dotted) set to `value`, or deleted when value is undefined. */
function withField(path, value) {
  const c = valid();
  const keys = path.split('.');
  let o = c;
  for (const k of keys.slice(0, -1)) o = o[k];
  if (value === undefined) delete o[keys.at(-1)];
  else o[keys.at(-1)] = value;
  return c;
}

test('a valid config parses, from text or object, with defaults filled', () => {
  const c = parseDepthConfig(JSON.stringify(valid()));
  assert.equal(c.input.width, 64);
  assert.equal(c.input.layout, 'NCHW');
  assert.equal(c.input.name, null);
  assert.deepEqual(c.normalize.std, [0.229, 0.224, 0.225]);
  assert.equal(c.output.kind, 'metric_depth');
  assert.equal(c.output.multiplier, 1);
  assert.equal(c.output.offset, 0);
  assert.ok(Object.isFrozen(c) && Object.isFrozen(c.input));
  assert.deepEqual(parseDepthConfig(c), c); // idempotent
  const named = parseDepthConfig(withField('output.name', 'predicted_depth'));
  assert.equal(named.output.name, 'predicted_depth');
  assert.equal(parseDepthConfig(withField('output.kind', 'metric_inverse_depth')).output.kind, 'metric_inverse_depth');
  assert.equal(parseDepthConfig(withField('input.layout', 'NHWC')).input.layout, 'NHWC');
});

const cases = [
  ['not JSON', '{"format": ', /not valid JSON/],
  ['an array', '[1, 2]', /must be a JSON object, got an array/],
  ['no format', withField('format', undefined), /'format' is missing/],
  ['wrong format', withField('format', 'onnx'), /'format' must be "hawor-depth-model", got "onnx"/],
  ['no version', withField('version', undefined), /'version' is missing/],
  ['version 2', withField('version', 2), /'version' must be 1, got number 2/],
  ['unknown top-level field', withField('inputs', {}), /'inputs' is not a known field/],
  ['no input', withField('input', undefined), /'input' is missing/],
  ['input not an object', withField('input', [64, 48]), /'input' must be an object, got an array/],
  ['no width', withField('input.width', undefined), /'input.width' is missing/],
  ['width a string', withField('input.width', '64'), /'input.width' must be an integer, got "64"/],
  ['width fractional', withField('input.width', 64.5), /'input.width' must be an integer/],
  ['width zero', withField('input.width', 0), /'input.width' must be positive, got 0/],
  ['height negative', withField('input.height', -48), /'input.height' must be positive, got -48/],
  ['height huge', withField('input.height', 100000), /'input.height' is 100000, more than 16384/],
  ['no layout', withField('input.layout', undefined), /'input.layout' is missing/],
  ['bad layout', withField('input.layout', 'CHW'), /'input.layout' must be "NCHW" or "NHWC", got "CHW"/],
  ['input name not a string', withField('input.name', 5), /'input.name' must be a non-empty string/],
  ['input name empty', withField('input.name', ''), /'input.name' must be a non-empty string/],
  ['unknown input field', withField('input.channels', 3), /'input.channels' is not a known field/],
  ['no normalize', withField('normalize', undefined), /'normalize' is missing/],
  ['no scale', withField('normalize.scale', undefined), /'normalize.scale' is missing/],
  ['scale zero', withField('normalize.scale', 0), /'normalize.scale' must be positive/],
  ['scale a string', withField('normalize.scale', '1/255'), /'normalize.scale' must be a finite number/],
  ['no mean', withField('normalize.mean', undefined), /'normalize.mean' is missing/],
  ['mean of 2', withField('normalize.mean', [0, 0]), /'normalize.mean' must be an array of 3 numbers/],
  ['mean with a string', withField('normalize.mean', [0, 'a', 0]), /'normalize.mean\[1\]' must be a finite number/],
  ['std zero', withField('normalize.std', [1, 0, 1]), /'normalize.std\[1\]' must not be 0/],
  ['std infinite', withField('normalize.std', [1, 1, Infinity]), /'normalize.std\[2\]' must be a finite number/],
  ['no output', withField('output', undefined), /'output' is missing/],
  ['no kind', withField('output.kind', undefined), /'output.kind' is missing \(must be one of metric_depth, metric_inverse_depth\)/],
  ['unknown kind', withField('output.kind', 'depth'), /'output.kind' must be one of metric_depth, metric_inverse_depth, got "depth"/],
  ['kind not a string', withField('output.kind', 1), /'output.kind' must be a string/],
  ['relative depth', withField('output.kind', 'relative_depth'), /'output.kind' "relative_depth" is refused: a relative or affine-invariant depth has an unknown scale/],
  ['affine-invariant inverse depth', withField('output.kind', 'affine_invariant_inverse_depth'), /is refused.*cannot give metres/],
  ['disparity', withField('output.kind', 'disparity'), /is refused/],
  ['multiplier zero', withField('output.multiplier', 0), /'output.multiplier' must not be 0/],
  ['multiplier a string', withField('output.multiplier', '2'), /'output.multiplier' must be a finite number, got "2"/],
  ['offset NaN', withField('output.offset', NaN), /'output.offset' must be a finite number/],
  ['misspelt multiplier', withField('output.mutliplier', 2), /'output.mutliplier' is not a known field/],
  ['output name not a string', withField('output.name', ['a']), /'output.name' must be a non-empty string/],
];

for (const [name, input, pattern] of cases) {
  test(`config error: ${name}`, () => {
    assert.throws(() => parseDepthConfig(input), (e) => {
      assert.match(e.message, /^depth config: /);
      assert.match(e.message, pattern);
      return true;
    });
  });
}
