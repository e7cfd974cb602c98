// onnx_builder.mjs: writes ONNX models (ModelProto) from JavaScript, with no dependency.
//
// ONNX files are protobuf messages (onnx/onnx.proto, proto2 syntax). This module encodes the
// subset a feed-forward network needs, straight into the protobuf wire format:
//   varint (wire type 0), 64-bit (1), length-delimited (2: strings, bytes, sub-messages,
//   packed repeated scalars) and 32-bit (5: float); a field's key is (number << 3) | wire type.
// Field numbers below are those of onnx.proto; each is cited next to the code that writes it.
//
// Usage:
//   import { OnnxGraph, attr } from './onnx_builder.mjs';
//   const g = new OnnxGraph('tiny');
//   g.addInput('x', 'float32', ['batch', 4]);          // a string is a symbolic dim (dim_param)
//   g.addInitializer('W', [4, 2], new Float32Array(8));
//   g.addNode('MatMul', ['x', 'W'], ['y']);
//   g.addNode('Softmax', ['y'], ['p'], { axis: -1 });
//   g.addOutput('p', 'float32', ['batch', 2]);
//   const bytes = g.toBytes({ opsetVersion: 17 });      // Uint8Array: a complete .onnx file
//
// Attribute values: a plain JS integer is an INT, any other number a FLOAT, a string a STRING,
// an array of integers INTS, an array with a non-integer (or a Float32Array) FLOATS. Where that
// guess is wrong (a FLOAT attribute whose value is 1, an empty list), say it: attr.float(1),
// attr.ints([]), attr.floats([]), attr.tensor(dims, data), attr.string(s), attr.int(n).

// ---------------------------------------------------------------------------------------------
// Protobuf wire format

const WIRE_VARINT = 0;
const WIRE_LEN = 2;
const WIRE_FIXED32 = 5;

const textEncoder = new TextEncoder();

/** Appends protobuf fields to a growing byte buffer. */
export class ProtoWriter {
  constructor() {
    this.buf = new Uint8Array(64);
    this.len = 0;
  }

  reserve(n) {
    if (this.len + n <= this.buf.length) return;
    let cap = this.buf.length * 2;
    while (cap < this.len + n) cap *= 2;
    const next = new Uint8Array(cap);
    next.set(this.buf.subarray(0, this.len));
    this.buf = next;
  }

  byte(b) {
    this.reserve(1);
    this.buf[this.len++] = b;
  }

  raw(bytes) {
    this.reserve(bytes.length);
    this.buf.set(bytes, this.len);
    this.len += bytes.length;
  }

  /** Base-128 varint of an integer in [-2^63, 2^64): 7 bits a byte, low bits first, MSB =
   *  "more follows". Negative int64 values are written as their 64-bit two's complement
   *  (10 bytes), as protobuf does for int32/int64 fields. */
  varint(value) {
    if (typeof value === 'number') {
      if (!Number.isSafeInteger(value)) throw new Error(`onnx_builder: ${value} is not a safe integer`);
      if (value >= 0) {
        let v = value;
        while (v >= 0x80) {
          this.byte((v % 0x80) | 0x80);
          v = Math.floor(v / 0x80);
        }
        this.byte(v);
        return;
      }
      value = BigInt(value);
    }
    if (typeof value !== 'bigint') throw new Error(`onnx_builder: varint of a ${typeof value}`);
    if (value < -(1n << 63n) || value >= (1n << 64n)) throw new Error(`onnx_builder: ${value} does not fit 64 bits`);
    let v = BigInt.asUintN(64, value);
    while (v >= 0x80n) {
      this.byte(Number(v & 0x7fn) | 0x80);
      v >>= 7n;
    }
    this.byte(Number(v));
  }

  key(field, wire) {
    this.varint(field * 8 + wire);
  }

  /** int32 / int64 / enum field (wire type 0). */
  int(field, value) {
    this.key(field, WIRE_VARINT);
    this.varint(value);
  }

  /** float field (wire type 5, IEEE 754 single, little-endian). */
  float(field, value) {
    this.key(field, WIRE_FIXED32);
    this.reserve(4);
    new DataView(this.buf.buffer, this.buf.byteOffset + this.len, 4).setFloat32(0, value, true);
    this.len += 4;
  }

  /** bytes field (wire type 2: length varint, then the bytes). */
  bytes(field, bytes) {
    this.key(field, WIRE_LEN);
    this.varint(bytes.length);
    this.raw(bytes);
  }

  /** string field: UTF-8 bytes. */
  string(field, s) {
    this.bytes(field, textEncoder.encode(s));
  }

  /** Embedded message: `fill(writer)` writes the sub-message's fields. */
  message(field, fill) {
    const sub = new ProtoWriter();
    fill(sub);
    this.bytes(field, sub.finish());
  }

  finish() {
    return this.buf.slice(0, this.len);
  }
}

// ---------------------------------------------------------------------------------------------
// ONNX enums

/** TensorProto.DataType (onnx.proto): element type names -> enum values. */
export const DataType = Object.freeze({
  float32: 1, // FLOAT
  uint8: 2, // UINT8
  int8: 3, // INT8
  uint16: 4, // UINT16
  int16: 5, // INT16
  int32: 6, // INT32
  int64: 7, // INT64
  bool: 9, // BOOL
  float16: 10, // FLOAT16
  float64: 11, // DOUBLE
  uint32: 12, // UINT32
  uint64: 13, // UINT64
});

/** AttributeProto.AttributeType (onnx.proto). */
const AttrType = Object.freeze({ FLOAT: 1, INT: 2, STRING: 3, TENSOR: 4, FLOATS: 6, INTS: 7, STRINGS: 8 });

function dataTypeOf(name) {
  const t = DataType[name];
  if (t === undefined) throw new Error(`onnx_builder: unknown element type '${name}' (one of ${Object.keys(DataType).join(', ')})`);
  return t;
}

// ---------------------------------------------------------------------------------------------
// Tensors

/** A constant tensor: dims (array of non-negative integers) and its data, row-major.
 *  Float32Array -> float32, BigInt64Array -> int64, Int32Array -> int32, Uint8Array -> uint8,
 *  Uint16Array -> float16 (half-float bit patterns) or uint16, as `type` says;
 *  a plain array needs `type` ('float32', 'int64', 'int32', 'uint8', 'bool'). */
function makeTensor(name, dims, data, type) {
  if (!Array.isArray(dims)) throw new Error(`onnx_builder: tensor '${name}': dims must be an array`);
  for (const d of dims) {
    if (!Number.isSafeInteger(d) || d < 0) throw new Error(`onnx_builder: tensor '${name}': dim ${d} is not a non-negative integer`);
  }
  const count = dims.reduce((a, b) => a * b, 1);
  let typed;
  if (data instanceof Float32Array) { typed = data; type = type ?? 'float32'; }
  else if (data instanceof BigInt64Array) { typed = data; type = type ?? 'int64'; }
  else if (data instanceof Int32Array) { typed = data; type = type ?? 'int32'; }
  else if (data instanceof Uint8Array) { typed = data; type = type ?? 'uint8'; }
  else if (data instanceof Uint16Array) {
    // 16-bit words: IEEE half floats (bit patterns) or uint16; which one must be said.
    if (type !== 'float16' && type !== 'uint16') throw new Error(`onnx_builder: tensor '${name}': a Uint16Array needs type float16 or uint16`);
    typed = data;
  }
  else if (Array.isArray(data)) {
    if (type === 'float32') typed = Float32Array.from(data);
    else if (type === 'int64') typed = BigInt64Array.from(data, (v) => BigInt(v));
    else if (type === 'int32') typed = Int32Array.from(data);
    else if (type === 'uint8' || type === 'bool') typed = Uint8Array.from(data, (v) => Number(v));
    else throw new Error(`onnx_builder: tensor '${name}': a plain array needs type float32, int64, int32, uint8 or bool`);
  } else {
    throw new Error(`onnx_builder: tensor '${name}': data must be a Float32Array, BigInt64Array, Int32Array, Uint8Array, Uint16Array or an array`);
  }
  if (typed.length !== count) {
    throw new Error(`onnx_builder: tensor '${name}': ${typed.length} values for dims [${dims.join(', ')}] (${count} expected)`);
  }
  // raw_data is little-endian (onnx.proto); typed arrays use the platform's order, which is
  // little-endian on every platform node and the browsers run on. Check rather than assume.
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] !== 1) throw new Error('onnx_builder: big-endian platform');
  const raw = new Uint8Array(typed.buffer, typed.byteOffset, typed.byteLength).slice();
  return { name, dims: dims.slice(), dataType: dataTypeOf(type), raw };
}

/** TensorProto: dims = 1 (repeated int64, unpacked), data_type = 2, name = 8, raw_data = 9. */
function writeTensor(w, t) {
  for (const d of t.dims) w.int(1, d);
  w.int(2, t.dataType);
  if (t.name) w.string(8, t.name);
  w.bytes(9, t.raw);
}

// ---------------------------------------------------------------------------------------------
// Attributes

const ATTR = Symbol('onnx attribute');

/** Explicitly typed attribute values, for when the plain-value guess is not what you want. */
export const attr = Object.freeze({
  int: (v) => ({ [ATTR]: AttrType.INT, value: v }),
  float: (v) => ({ [ATTR]: AttrType.FLOAT, value: v }),
  string: (v) => ({ [ATTR]: AttrType.STRING, value: v }),
  ints: (v) => ({ [ATTR]: AttrType.INTS, value: Array.from(v) }),
  floats: (v) => ({ [ATTR]: AttrType.FLOATS, value: Array.from(v) }),
  strings: (v) => ({ [ATTR]: AttrType.STRINGS, value: Array.from(v) }),
  /** A tensor attribute (e.g. Constant's `value`). */
  tensor: (dims, data, type) => ({ [ATTR]: AttrType.TENSOR, value: makeTensor('', dims, data, type) }),
});

function typedAttr(name, v) {
  if (v !== null && typeof v === 'object' && v[ATTR] !== undefined) return { type: v[ATTR], value: v.value };
  if (typeof v === 'bigint') return { type: AttrType.INT, value: v };
  if (typeof v === 'number') return { type: Number.isInteger(v) ? AttrType.INT : AttrType.FLOAT, value: v };
  if (typeof v === 'string') return { type: AttrType.STRING, value: v };
  if (v instanceof Float32Array || v instanceof Float64Array) return { type: AttrType.FLOATS, value: Array.from(v) };
  if (Array.isArray(v)) {
    if (v.length === 0) throw new Error(`onnx_builder: attribute '${name}': an empty list needs attr.ints([]) or attr.floats([])`);
    if (v.every((x) => typeof x === 'string')) return { type: AttrType.STRINGS, value: v };
    if (v.every((x) => typeof x === 'bigint' || Number.isInteger(x))) return { type: AttrType.INTS, value: v };
    if (v.every((x) => typeof x === 'number')) return { type: AttrType.FLOATS, value: v };
  }
  throw new Error(`onnx_builder: attribute '${name}': cannot encode ${String(v)}`);
}

/** AttributeProto: name = 1, f = 2, i = 3, s = 4, t = 5, floats = 7 (repeated float, unpacked),
 *  ints = 8 (repeated int64, unpacked), strings = 9, type = 20. */
function writeAttribute(w, name, a) {
  w.string(1, name);
  switch (a.type) {
    case AttrType.FLOAT: w.float(2, a.value); break;
    case AttrType.INT: w.int(3, a.value); break;
    case AttrType.STRING: w.string(4, a.value); break;
    case AttrType.TENSOR: w.message(5, (t) => writeTensor(t, a.value)); break;
    case AttrType.FLOATS: for (const x of a.value) w.float(7, x); break;
    case AttrType.INTS: for (const x of a.value) w.int(8, x); break;
    case AttrType.STRINGS: for (const x of a.value) w.string(9, x); break;
    default: throw new Error(`onnx_builder: attribute '${name}': unsupported type ${a.type}`);
  }
  w.int(20, a.type);
}

// ---------------------------------------------------------------------------------------------
// Value infos

function checkShape(what, shape) {
  if (shape === null || shape === undefined) return null; // rank unknown: no shape field
  if (!Array.isArray(shape)) throw new Error(`onnx_builder: ${what}: shape must be an array (or null)`);
  for (const d of shape) {
    const ok = (Number.isSafeInteger(d) && d >= 0) || (typeof d === 'string' && d.length > 0) || d === null;
    if (!ok) throw new Error(`onnx_builder: ${what}: dim ${d} is neither a non-negative integer nor a symbolic name`);
  }
  return shape.slice();
}

/** ValueInfoProto: name = 1, type = 2 -> TypeProto.tensor_type = 1 -> Tensor{elem_type = 1,
 *  shape = 2 -> TensorShapeProto.dim = 1 -> Dimension{dim_value = 1 | dim_param = 2}}.
 *  A null dim writes an empty Dimension (unknown, unnamed). */
function writeValueInfo(w, v) {
  w.string(1, v.name);
  w.message(2, (type) => {
    type.message(1, (tensor) => {
      tensor.int(1, v.dataType);
      if (v.shape !== null) {
        tensor.message(2, (shape) => {
          for (const d of v.shape) {
            shape.message(1, (dim) => {
              if (typeof d === 'number') dim.int(1, d);
              else if (typeof d === 'string') dim.string(2, d);
            });
          }
        });
      }
    });
  });
}

// ---------------------------------------------------------------------------------------------
// Graph and model

/** A computation graph under construction. Names are checked as they are added: every node
 *  input must be a graph input, an initializer or an earlier node's output ('' = an omitted
 *  optional input), and every value is produced once, so a wiring mistake fails here with its
 *  name instead of as an opaque onnxruntime load error. */
export class OnnxGraph {
  constructor(name = 'graph') {
    this.name = name;
    this.nodes = [];
    this.inputs = [];
    this.outputs = [];
    this.initializers = [];
    this.valueInfos = [];
    this.defined = new Set();
    this.nodeCount = 0;
  }

  define(name, what) {
    if (typeof name !== 'string' || name.length === 0) throw new Error(`onnx_builder: ${what}: name must be a non-empty string`);
    if (this.defined.has(name)) throw new Error(`onnx_builder: ${what}: value '${name}' is already defined`);
    this.defined.add(name);
  }

  /** A graph input: element type name (see DataType) and shape (integers, symbolic names, or
   *  null for an unknown dim; shape null = rank unknown). Returns `name`. */
  addInput(name, elemType = 'float32', shape = null) {
    this.define(name, `input '${name}'`);
    this.inputs.push({ name, dataType: dataTypeOf(elemType), shape: checkShape(`input '${name}'`, shape) });
    return name;
  }

  /** A graph output: an existing value (input, initializer or node output). Returns `name`. */
  addOutput(name, elemType = 'float32', shape = null) {
    if (!this.defined.has(name)) throw new Error(`onnx_builder: output '${name}' is not produced by the graph`);
    if (this.outputs.some((o) => o.name === name)) throw new Error(`onnx_builder: output '${name}' is listed twice`);
    this.outputs.push({ name, dataType: dataTypeOf(elemType), shape: checkShape(`output '${name}'`, shape) });
    return name;
  }

  /** Optional type/shape of an intermediate value (GraphProto.value_info). */
  addValueInfo(name, elemType = 'float32', shape = null) {
    this.valueInfos.push({ name, dataType: dataTypeOf(elemType), shape: checkShape(`value_info '${name}'`, shape) });
    return name;
  }

  /** A constant (weights): see makeTensor for the accepted data. Returns `name`. */
  addInitializer(name, dims, data, type) {
    this.define(name, `initializer '${name}'`);
    this.initializers.push(makeTensor(name, dims, data, type));
    return name;
  }

  /** A node `op` (ONNX operator name, e.g. 'MatMul') reading `inputs`, writing `outputs`, with
   *  attributes `attrs` ({name: value}, see the header). `options.name` names the node (default
   *  op_N), `options.domain` picks a non-default operator set. Returns the outputs array. */
  addNode(op, inputs, outputs, attrs = {}, options = {}) {
    if (typeof op !== 'string' || op.length === 0) throw new Error('onnx_builder: addNode: op must be a non-empty string');
    if (!Array.isArray(inputs) || !Array.isArray(outputs)) throw new Error(`onnx_builder: ${op}: inputs and outputs must be arrays`);
    const nodeName = options.name ?? `${op}_${this.nodeCount}`;
    for (const i of inputs) {
      if (i === '') continue;
      if (!this.defined.has(i)) throw new Error(`onnx_builder: node '${nodeName}' (${op}): input '${i}' is not defined yet`);
    }
    if (outputs.length === 0) throw new Error(`onnx_builder: node '${nodeName}' (${op}) has no output`);
    for (const o of outputs) this.define(o, `node '${nodeName}' (${op}) output`);
    const typedAttrs = Object.entries(attrs).map(([k, v]) => [k, typedAttr(k, v)]);
    this.nodes.push({ op, inputs: inputs.slice(), outputs: outputs.slice(), name: nodeName, domain: options.domain ?? '', attrs: typedAttrs });
    this.nodeCount += 1;
    return outputs;
  }

  /** GraphProto: node = 1, name = 2, initializer = 5, input = 11, output = 12, value_info = 13.
   *  NodeProto: input = 1, output = 2, name = 3, op_type = 4, attribute = 5, domain = 7. */
  encodeGraph(w) {
    if (this.outputs.length === 0) throw new Error(`onnx_builder: graph '${this.name}' has no output`);
    for (const n of this.nodes) {
      w.message(1, (nw) => {
        for (const i of n.inputs) nw.string(1, i);
        for (const o of n.outputs) nw.string(2, o);
        nw.string(3, n.name);
        nw.string(4, n.op);
        for (const [k, a] of n.attrs) nw.message(5, (aw) => writeAttribute(aw, k, a));
        if (n.domain) nw.string(7, n.domain);
      });
    }
    w.string(2, this.name);
    for (const t of this.initializers) w.message(5, (tw) => writeTensor(tw, t));
    for (const v of this.inputs) w.message(11, (vw) => writeValueInfo(vw, v));
    for (const v of this.outputs) w.message(12, (vw) => writeValueInfo(vw, v));
    for (const v of this.valueInfos) w.message(13, (vw) => writeValueInfo(vw, v));
  }

  /** The complete model file. ModelProto: ir_version = 1, producer_name = 2, producer_version
   *  = 3, doc_string = 6, graph = 7, opset_import = 8 (OperatorSetIdProto: domain = 1,
   *  version = 2). Defaults: opset 17 (has LayerNormalization), IR version 8 (the one that
   *  goes with opset 17). `extraOpsets`: [{domain, version}] for other operator sets. */
  toBytes({ opsetVersion = 17, irVersion = 8, producerName = 'hawor', producerVersion = '0.1', docString = '', extraOpsets = [] } = {}) {
    const w = new ProtoWriter();
    w.int(1, irVersion);
    w.string(2, producerName);
    w.string(3, producerVersion);
    if (docString) w.string(6, docString);
    w.message(7, (gw) => this.encodeGraph(gw));
    w.message(8, (ow) => {
      ow.string(1, '');
      ow.int(2, opsetVersion);
    });
    for (const o of extraOpsets) {
      w.message(8, (ow) => {
        ow.string(1, o.domain);
        ow.int(2, o.version);
      });
    }
    return w.finish();
  }
}
