// tflite_writer.mjs: writes small TFLite models (FlatBuffers of tensorflow/lite/schema/schema.fbs)
// for the converter's op-by-op tests. Not a test file.
//
// Layout written: the root uoffset at byte 0, "TFL3" at 4, then tables parent-first. Every
// reference (uoffset, unsigned) points forward, so a table is written, then its children after
// it, and the reference slots are patched. Each table's vtable sits just before it
// (soffset = table - vtable > 0). Scalars are aligned to their size; byte vectors (tensor data)
// start on 16-byte boundaries (schema: force_align 16).

class Out {
  constructor() { this.buf = new Uint8Array(1024); this.len = 0; }
  ensure(n) {
    if (this.len + n <= this.buf.length) return;
    let cap = this.buf.length * 2;
    while (cap < this.len + n) cap *= 2;
    const b = new Uint8Array(cap); b.set(this.buf.subarray(0, this.len)); this.buf = b;
  }
  align(a) { while (this.len % a) { this.ensure(1); this.buf[this.len++] = 0; } }
  view() { return new DataView(this.buf.buffer); }
  u8(v) { this.ensure(1); this.buf[this.len++] = v & 255; }
  u16(v) { this.ensure(2); this.view().setUint16(this.len, v, true); this.len += 2; }
  u32(v) { this.ensure(4); this.view().setUint32(this.len, v >>> 0, true); this.len += 4; }
  i32(v) { this.ensure(4); this.view().setInt32(this.len, v, true); this.len += 4; }
  f32(v) { this.ensure(4); this.view().setFloat32(this.len, v, true); this.len += 4; }
  patchRef(at, target) { this.view().setUint32(at, target - at, true); }
}

// Field value makers: a table is an array indexed by field id of these (undefined = absent).
export const F = {
  u8: (v) => ({ k: 'u8', v, size: 1 }),
  bool: (v) => ({ k: 'u8', v: v ? 1 : 0, size: 1 }),
  i32: (v) => ({ k: 'i32', v, size: 4 }),
  u32: (v) => ({ k: 'u32', v, size: 4 }),
  table: (fields) => ({ k: 'ref', child: { kind: 'table', fields }, size: 4 }),
  tables: (list) => ({ k: 'ref', child: { kind: 'tables', list }, size: 4 }),
  ints: (arr) => ({ k: 'ref', child: { kind: 'ints', arr }, size: 4 }),
  bytes: (u8) => ({ k: 'ref', child: { kind: 'bytes', u8 }, size: 4 }),
  string: (s) => ({ k: 'ref', child: { kind: 'bytes', u8: new TextEncoder().encode(s), zero: true }, size: 4 }),
};

function writeChild(o, c) {
  if (c.kind === 'table') return writeTable(o, c.fields);
  if (c.kind === 'ints') {
    o.align(4);
    const p = o.len;
    o.u32(c.arr.length);
    for (const v of c.arr) o.i32(v);
    return p;
  }
  if (c.kind === 'bytes') {
    while ((o.len + 4) % 16) o.u8(0); // data after the length on a 16-byte boundary
    const p = o.len;
    o.u32(c.u8.length);
    o.ensure(c.u8.length + 1);
    o.buf.set(c.u8, o.len);
    o.len += c.u8.length;
    if (c.zero) o.u8(0);
    return p;
  }
  if (c.kind === 'tables') {
    o.align(4);
    const p = o.len;
    o.u32(c.list.length);
    const slots = c.list.map(() => { const at = o.len; o.u32(0); return at; });
    c.list.forEach((fields, i) => o.patchRef(slots[i], writeTable(o, fields)));
    return p;
  }
  throw new Error(`writer: child kind ${c.kind}`);
}

function writeTable(o, fields) {
  // table layout: soffset (4), then fields sorted by size (4-byte ones first), aligned
  const ids = fields.map((f, i) => (f ? i : -1)).filter((i) => i >= 0);
  const order = ids.slice().sort((a, b) => fields[b].size - fields[a].size);
  const offsets = new Map();
  let off = 4;
  for (const id of order) {
    const s = fields[id].size;
    off = Math.ceil(off / s) * s;
    offsets.set(id, off);
    off += s;
  }
  const tableSize = Math.ceil(off / 4) * 4;
  const nFields = fields.length;
  o.align(2);
  // the vtable must end where the 4-aligned table starts: pad before it
  const vtSize = 4 + 2 * nFields;
  while ((o.len + vtSize) % 4) o.u8(0);
  const vt = o.len;
  o.u16(vtSize);
  o.u16(tableSize);
  for (let i = 0; i < nFields; ++i) o.u16(offsets.get(i) ?? 0);
  const t = o.len;
  o.i32(t - vt);
  o.ensure(tableSize);
  o.buf.fill(0, o.len, t + tableSize);
  o.len = t + tableSize;
  const dv = o.view();
  const refs = [];
  for (const id of ids) {
    const f = fields[id];
    const at = t + offsets.get(id);
    if (f.k === 'u8') dv.setUint8(at, f.v & 255);
    else if (f.k === 'i32') dv.setInt32(at, f.v, true);
    else if (f.k === 'u32') dv.setUint32(at, f.v >>> 0, true);
    else refs.push([at, f.child]);
  }
  for (const [at, child] of refs) o.patchRef(at, writeChild(o, child));
  return t;
}

const OP_CODES = { ADD: 0, CONCATENATION: 2, CONV_2D: 3, DEPTHWISE_CONV_2D: 4, DEQUANTIZE: 6, FULLY_CONNECTED: 9, LOGISTIC: 14, MAX_POOL_2D: 17, MUL: 18, RESHAPE: 22, RESIZE_BILINEAR: 23, PAD: 34, MEAN: 40, PRELU: 54 };
const TYPES = { float32: 0, float16: 1, int32: 2 };
const ACT = { NONE: 0, RELU: 1, RELU_N1_TO_1: 2, RELU6: 3, TANH: 4 };
const PAD = { SAME: 0, VALID: 1 };

// op -> [BuiltinOptions union index, option table fields] (schema.fbs declaration order)
function options(op, o = {}) {
  const a = (x) => F.u8(ACT[x ?? 'NONE']);
  switch (op) {
    case 'CONV_2D': return [1, [F.u8(PAD[o.padding]), F.i32(o.strideW ?? 1), F.i32(o.strideH ?? 1), a(o.activation), F.i32(o.dilationW ?? 1), F.i32(o.dilationH ?? 1)]];
    case 'DEPTHWISE_CONV_2D': return [2, [F.u8(PAD[o.padding]), F.i32(o.strideW ?? 1), F.i32(o.strideH ?? 1), F.i32(o.depthMultiplier ?? 1), a(o.activation), F.i32(o.dilationW ?? 1), F.i32(o.dilationH ?? 1)]];
    case 'MAX_POOL_2D': return [5, [F.u8(PAD[o.padding]), F.i32(o.strideW), F.i32(o.strideH), F.i32(o.filterW), F.i32(o.filterH), a(o.activation)]];
    case 'FULLY_CONNECTED': return [8, [a(o.activation), F.u8(0), F.bool(!!o.keepNumDims)]];
    case 'CONCATENATION': return [10, [F.i32(o.axis), a(o.activation)]];
    case 'ADD': return [11, [a(o.activation)]];
    case 'RESIZE_BILINEAR': return [15, [undefined, undefined, F.bool(!!o.alignCorners), F.bool(!!o.halfPixelCenters)]];
    case 'RESHAPE': return o.newShape ? [17, [F.ints(o.newShape)]] : [0, null];
    case 'PAD': return [22, []];
    case 'MEAN': return [27, [F.bool(!!o.keepDims)]];
    case 'DEQUANTIZE': return [38, []];
    default: return [0, null]; // LOGISTIC, PRELU, MUL: no options
  }
}

/**
 * A TFLite model from a plain description:
 *   tensors: [{ name, shape, type ('float32' | 'float16' | 'int32'), data (typed array, constants) }]
 *   inputs, outputs: tensor indices; ops: [{ op (name), inputs, outputs, options }]
 * Returns the .tflite bytes (Uint8Array).
 */
export function writeTflite({ tensors, inputs, outputs, ops }) {
  const opNames = [...new Set(ops.map((x) => x.op))];
  const buffers = [[]]; // buffer 0: the empty sentinel
  const tensorTables = tensors.map((t) => {
    let bufferIndex = 0;
    if (t.data) {
      buffers.push([F.bytes(new Uint8Array(t.data.buffer, t.data.byteOffset, t.data.byteLength))]);
      bufferIndex = buffers.length - 1;
    }
    // Tensor: shape(0), type(1), buffer(2), name(3)
    return [F.ints(t.shape), F.u8(TYPES[t.type ?? 'float32']), F.u32(bufferIndex), F.string(t.name)];
  });
  const opTables = ops.map((x) => {
    const [ut, fields] = options(x.op, x.options);
    // Operator: opcode_index(0), inputs(1), outputs(2), builtin_options_type(3), builtin_options(4)
    const f = [F.u32(opNames.indexOf(x.op)), F.ints(x.inputs), F.ints(x.outputs)];
    if (ut) { f[3] = F.u8(ut); f[4] = F.table(fields); }
    return f;
  });
  // OperatorCode: deprecated_builtin_code(0, byte), custom_code(1), version(2), builtin_code(3)
  const codes = opNames.map((n) => [F.u8(OP_CODES[n]), undefined, F.i32(1), F.i32(OP_CODES[n])]);
  // SubGraph: tensors(0), inputs(1), outputs(2), operators(3), name(4)
  const subgraph = [F.tables(tensorTables), F.ints(inputs), F.ints(outputs), F.tables(opTables), F.string('main')];
  // Model: version(0), operator_codes(1), subgraphs(2), description(3), buffers(4)
  const model = [F.u32(3), F.tables(codes), F.tables([subgraph]), F.string('hawor test model'), F.tables(buffers)];
  const o = new Out();
  o.u32(0);
  for (const ch of 'TFL3') o.u8(ch.charCodeAt(0));
  o.patchRef(0, writeTable(o, model));
  return o.buf.slice(0, o.len);
}
