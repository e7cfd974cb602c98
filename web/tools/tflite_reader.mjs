// tflite_reader.mjs: reads a TFLite model (a FlatBuffer of tensorflow/lite/schema/schema.fbs)
// into plain JavaScript objects, with no dependency.
//
// FlatBuffers layout (little-endian): the file starts with a uoffset (u32) to the root table;
// bytes 4..8 hold the file identifier ("TFL3" for TFLite). A table at position p starts with an
// soffset (i32) s: its vtable is at p - s. A vtable is [u16 vtable size, u16 table size, u16
// field offset per field id...]; offset 0 (or a field id past the vtable's end) means "absent,
// use the default". Scalars sit inline at p + offset. Tables, vectors and strings are
// referenced by a uoffset (u32) stored at the field, relative to the field's own position.
// A vector is [u32 length, elements...]; a string is a vector of bytes (plus a trailing 0).
// A union occupies two field ids: the type (u8) and then the value (a table reference).
//
// Field ids below are the declaration order of schema.fbs (0 = first field of the table).
// Every read is bounds-checked, so a corrupt or truncated file fails with an Error naming what
// was being read, never with garbage or a hang.

/** schema.fbs enum TensorType. */
export const TensorType = Object.freeze({
  0: 'float32', 1: 'float16', 2: 'int32', 3: 'uint8', 4: 'int64', 5: 'string', 6: 'bool',
  7: 'int16', 8: 'complex64', 9: 'int8', 10: 'float64', 11: 'complex128', 12: 'uint64',
  13: 'resource', 14: 'variant', 15: 'uint32', 16: 'uint16', 17: 'int4',
});

/** schema.fbs enum BuiltinOperator: the codes of the ops this project meets, plus those whose
 *  name helps an error message ("unsupported op MUL" rather than "unsupported op 18"). */
export const BuiltinOperator = Object.freeze({
  0: 'ADD', 1: 'AVERAGE_POOL_2D', 2: 'CONCATENATION', 3: 'CONV_2D', 4: 'DEPTHWISE_CONV_2D',
  5: 'DEPTH_TO_SPACE', 6: 'DEQUANTIZE', 7: 'EMBEDDING_LOOKUP', 8: 'FLOOR', 9: 'FULLY_CONNECTED',
  10: 'HASHTABLE_LOOKUP', 11: 'L2_NORMALIZATION', 12: 'L2_POOL_2D',
  13: 'LOCAL_RESPONSE_NORMALIZATION', 14: 'LOGISTIC', 15: 'LSH_PROJECTION', 16: 'LSTM',
  17: 'MAX_POOL_2D', 18: 'MUL', 19: 'RELU', 20: 'RELU_N1_TO_1', 21: 'RELU6', 22: 'RESHAPE',
  23: 'RESIZE_BILINEAR', 24: 'RNN', 25: 'SOFTMAX', 26: 'SPACE_TO_DEPTH', 27: 'SVDF', 28: 'TANH',
  32: 'CUSTOM', 34: 'PAD', 36: 'GATHER', 39: 'TRANSPOSE', 40: 'MEAN', 41: 'SUB', 42: 'DIV',
  43: 'SQUEEZE', 45: 'STRIDED_SLICE', 47: 'EXP', 49: 'SPLIT', 53: 'CAST', 54: 'PRELU',
  55: 'MAXIMUM', 57: 'MINIMUM', 60: 'PADV2', 65: 'SLICE', 67: 'TRANSPOSE_CONV', 74: 'SUM',
  83: 'PACK', 97: 'RESIZE_NEAREST_NEIGHBOR', 98: 'LEAKY_RELU', 114: 'QUANTIZE', 117: 'HARD_SWISH',
});

/** schema.fbs enum ActivationFunctionType. */
export const Activation = Object.freeze({ 0: 'NONE', 1: 'RELU', 2: 'RELU_N1_TO_1', 3: 'RELU6', 4: 'TANH', 5: 'SIGN_BIT' });

/** schema.fbs enum Padding. */
export const Padding = Object.freeze({ 0: 'SAME', 1: 'VALID' });

// union BuiltinOptions: the member index (1-based: 0 is NONE) -> how to read that table.
// Each reader gets a Table and returns a plain object of the option fields.
const act = (t, id) => {
  const a = t.u8(id, 0);
  return Activation[a] ?? `ACTIVATION_${a}`;
};
const pad = (t, id) => {
  const p = t.u8(id, 0);
  return Padding[p] ?? `PADDING_${p}`;
};
const OPTION_READERS = {
  // Conv2DOptions: padding, stride_w, stride_h, fused_activation_function,
  //                dilation_w_factor = 1, dilation_h_factor = 1
  1: ['Conv2DOptions', (t) => ({
    padding: pad(t, 0), strideW: t.i32(1, 0), strideH: t.i32(2, 0), activation: act(t, 3),
    dilationW: t.i32(4, 1), dilationH: t.i32(5, 1),
  })],
  // DepthwiseConv2DOptions: padding, stride_w, stride_h, depth_multiplier,
  //                         fused_activation_function, dilation_w_factor = 1, dilation_h_factor = 1
  2: ['DepthwiseConv2DOptions', (t) => ({
    padding: pad(t, 0), strideW: t.i32(1, 0), strideH: t.i32(2, 0), depthMultiplier: t.i32(3, 0),
    activation: act(t, 4), dilationW: t.i32(5, 1), dilationH: t.i32(6, 1),
  })],
  // Pool2DOptions: padding, stride_w, stride_h, filter_width, filter_height, fused_activation_function
  5: ['Pool2DOptions', (t) => ({
    padding: pad(t, 0), strideW: t.i32(1, 0), strideH: t.i32(2, 0), filterW: t.i32(3, 0),
    filterH: t.i32(4, 0), activation: act(t, 5),
  })],
  // FullyConnectedOptions: fused_activation_function, weights_format, keep_num_dims,
  //                        asymmetric_quantize_inputs
  8: ['FullyConnectedOptions', (t) => ({
    activation: act(t, 0), weightsFormat: t.u8(1, 0), keepNumDims: t.bool(2, false),
  })],
  // ConcatenationOptions: axis, fused_activation_function
  10: ['ConcatenationOptions', (t) => ({ axis: t.i32(0, 0), activation: act(t, 1) })],
  // AddOptions: fused_activation_function, pot_scale_int16
  11: ['AddOptions', (t) => ({ activation: act(t, 0) })],
  // ResizeBilinearOptions: new_height (deprecated), new_width (deprecated), align_corners,
  //                        half_pixel_centers
  15: ['ResizeBilinearOptions', (t) => ({ alignCorners: t.bool(2, false), halfPixelCenters: t.bool(3, false) })],
  // ReshapeOptions: new_shape
  17: ['ReshapeOptions', (t) => ({ newShape: t.intVector(0) })],
  // PadOptions: no fields
  22: ['PadOptions', () => ({})],
  // ReducerOptions: keep_dims
  27: ['ReducerOptions', (t) => ({ keepDims: t.bool(0, false) })],
  // DequantizeOptions: no fields
  38: ['DequantizeOptions', () => ({})],
};

/** Bounds-checked little-endian access to the file's bytes. */
class Bytes {
  constructor(u8) {
    this.u8 = u8;
    this.view = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
  }

  check(pos, n, what) {
    if (!Number.isInteger(pos) || pos < 0 || pos + n > this.u8.length) {
      throw new Error(`tflite: corrupt file: ${what} at byte ${pos} (+${n}) lies outside the ${this.u8.length}-byte file`);
    }
  }

  getU8(pos, what) { this.check(pos, 1, what); return this.view.getUint8(pos); }
  getU16(pos, what) { this.check(pos, 2, what); return this.view.getUint16(pos, true); }
  getI32(pos, what) { this.check(pos, 4, what); return this.view.getInt32(pos, true); }
  getU32(pos, what) { this.check(pos, 4, what); return this.view.getUint32(pos, true); }
  getF32(pos, what) { this.check(pos, 4, what); return this.view.getFloat32(pos, true); }

  /** Table at position pos (found by following a reference); `what` names it in errors. */
  table(pos, what) {
    const vt = pos - this.getI32(pos, `${what} (vtable offset)`);
    const vtSize = this.getU16(vt, `${what} (vtable size)`);
    const tableSize = this.getU16(vt + 2, `${what} (table size)`);
    if (vtSize < 4 || vtSize % 2 !== 0) throw new Error(`tflite: corrupt file: ${what} has a vtable of ${vtSize} bytes`);
    this.check(vt, vtSize, `${what} (vtable)`);
    this.check(pos, tableSize, `${what} (table)`);
    return new Table(this, pos, vt, vtSize, tableSize, what);
  }
}

class Table {
  constructor(bytes, pos, vt, vtSize, tableSize, what) {
    Object.assign(this, { bytes, pos, vt, vtSize, tableSize, what });
  }

  /** Position of field `id`, or 0 when absent. */
  field(id, size) {
    const at = 4 + 2 * id;
    if (at + 2 > this.vtSize) return 0;
    const off = this.bytes.getU16(this.vt + at, `${this.what} field ${id}`);
    if (off === 0) return 0;
    if (off + size > this.tableSize) {
      throw new Error(`tflite: corrupt file: ${this.what} field ${id} at offset ${off} lies outside its ${this.tableSize}-byte table`);
    }
    return this.pos + off;
  }

  u8(id, dflt) { const p = this.field(id, 1); return p ? this.bytes.getU8(p, `${this.what} field ${id}`) : dflt; }
  i8(id, dflt) { const v = this.u8(id, dflt); return v > 127 ? v - 256 : v; }
  bool(id, dflt) { return this.u8(id, dflt ? 1 : 0) !== 0; }
  i32(id, dflt) { const p = this.field(id, 4); return p ? this.bytes.getI32(p, `${this.what} field ${id}`) : dflt; }
  u32(id, dflt) { const p = this.field(id, 4); return p ? this.bytes.getU32(p, `${this.what} field ${id}`) : dflt; }

  /** Target position of the reference in field id (0 when absent). */
  ref(id) {
    const p = this.field(id, 4);
    if (!p) return 0;
    return p + this.bytes.getU32(p, `${this.what} field ${id} (reference)`);
  }

  /** [position of element 0, length] of a vector field with elements of `elemSize` bytes. */
  vector(id, elemSize, what) {
    const p = this.ref(id);
    if (!p) return null;
    const n = this.bytes.getU32(p, `${what} (length)`);
    this.bytes.check(p + 4, n * elemSize, `${what} (${n} elements)`);
    return [p + 4, n];
  }

  intVector(id) {
    const v = this.vector(id, 4, `${this.what} field ${id}`);
    if (!v) return null;
    const out = new Array(v[1]);
    for (let i = 0; i < v[1]; ++i) out[i] = this.bytes.getI32(v[0] + 4 * i, `${this.what} field ${id}`);
    return out;
  }

  floatVector(id) {
    const v = this.vector(id, 4, `${this.what} field ${id}`);
    if (!v) return null;
    const out = new Array(v[1]);
    for (let i = 0; i < v[1]; ++i) out[i] = this.bytes.getF32(v[0] + 4 * i, `${this.what} field ${id}`);
    return out;
  }

  byteVector(id) {
    const v = this.vector(id, 1, `${this.what} field ${id}`);
    if (!v) return null;
    return this.bytes.u8.subarray(v[0], v[0] + v[1]);
  }

  string(id) {
    const b = this.byteVector(id);
    return b === null ? null : new TextDecoder().decode(b);
  }

  /** The tables of a vector-of-tables field. */
  tables(id, what) {
    const v = this.vector(id, 4, what);
    if (!v) return [];
    const out = new Array(v[1]);
    for (let i = 0; i < v[1]; ++i) {
      const p = v[0] + 4 * i;
      out[i] = this.bytes.table(p + this.bytes.getU32(p, `${what}[${i}] (reference)`), `${what}[${i}]`);
    }
    return out;
  }

  subtable(id, what) {
    const p = this.ref(id);
    return p ? this.bytes.table(p, what) : null;
  }
}

/**
 * Parses a .tflite file.
 * @param {Uint8Array} u8 the file's bytes
 * @returns {{version, description, tensors, inputs, outputs, operators}} the main subgraph:
 *   tensors[i] = {index, name, type ('float32', 'float16', ...), shape (array), data (Uint8Array
 *   view of the constant buffer, or null)}; operators[k] = {index, op (name, e.g. 'CONV_2D'),
 *   code (number), version, inputs (tensor indices, -1 = omitted), outputs, optionsType
 *   (union member name or null), options (object)}.
 */
export function readTflite(u8) {
  if (!(u8 instanceof Uint8Array)) throw new Error('tflite: expected the file as a Uint8Array');
  if (u8.length < 8) throw new Error(`tflite: ${u8.length} bytes is too short for a TFLite file`);
  const ident = String.fromCharCode(u8[4], u8[5], u8[6], u8[7]);
  if (ident !== 'TFL3') {
    throw new Error(`tflite: not a TFLite model: file identifier at bytes 4..8 is ${JSON.stringify(ident)}, expected "TFL3"`);
  }
  const bytes = new Bytes(u8);
  const model = bytes.table(bytes.getU32(0, 'root offset'), 'Model');

  // Model: version(0), operator_codes(1), subgraphs(2), description(3), buffers(4), ...
  const version = model.u32(0, 0);
  const description = model.string(3);
  // Buffer: data(0), offset(1, u64), size(2, u64); offset/size are for models over 2 GB whose
  // data lives after the FlatBuffer: not supported (ours are a few MB).
  const buffers = model.tables(4, 'Model.buffers').map((b, i) => {
    const off = b.field(1, 8);
    if (off && (b.bytes.getU32(off, 'Buffer.offset') !== 0 || b.bytes.getU32(off + 4, 'Buffer.offset') !== 0)) {
      throw new Error(`tflite: buffer ${i} stores its data outside the FlatBuffer (models over 2 GB): not supported`);
    }
    return b.byteVector(0);
  });
  // OperatorCode: deprecated_builtin_code(0, i8), custom_code(1), version(2) = 1, builtin_code(3, i32).
  // Writers put codes < 127 in the old byte field and newer ones in the int field; the code is
  // the larger of the two (what TFLite's own GetBuiltinCode does).
  const opcodes = model.tables(1, 'Model.operator_codes').map((c) => {
    const code = Math.max(c.i8(0, 0), c.i32(3, 0));
    return { code, name: BuiltinOperator[code] ?? `BUILTIN_${code}`, custom: c.string(1), version: c.i32(2, 1) };
  });
  const subgraphs = model.tables(2, 'Model.subgraphs');
  if (subgraphs.length === 0) throw new Error('tflite: the model has no subgraph');
  const sg = subgraphs[0];

  // SubGraph: tensors(0), inputs(1), outputs(2), operators(3), name(4).
  // Tensor: shape(0), type(1), buffer(2), name(3), quantization(4), is_variable(5), ...
  const tensors = sg.tables(0, 'SubGraph.tensors').map((t, index) => {
    const typeCode = t.i8(1, 0);
    const type = TensorType[typeCode] ?? `TYPE_${typeCode}`;
    const shape = t.intVector(0) ?? [];
    const bufferIndex = t.u32(2, 0);
    if (bufferIndex >= buffers.length) {
      throw new Error(`tflite: tensor ${index} refers to buffer ${bufferIndex} of ${buffers.length}`);
    }
    const raw = buffers[bufferIndex];
    const data = raw && raw.length > 0 ? raw : null;
    // QuantizationParameters: min(0), max(1), scale(2), zero_point(3), ...
    const q = t.subtable(4, `tensor ${index} quantization`);
    const scale = q ? q.floatVector(2) : null;
    return { index, name: t.string(3) ?? `tensor_${index}`, type, shape, data, quantized: !!(scale && scale.length) };
  });
  const checkIndex = (i, what) => {
    if (i !== -1 && (i < 0 || i >= tensors.length)) throw new Error(`tflite: ${what} refers to tensor ${i} of ${tensors.length}`);
    return i;
  };
  const inputs = (sg.intVector(1) ?? []).map((i) => checkIndex(i, 'subgraph input'));
  const outputs = (sg.intVector(2) ?? []).map((i) => checkIndex(i, 'subgraph output'));

  // Operator: opcode_index(0), inputs(1), outputs(2), builtin_options_type(3),
  //           builtin_options(4), custom_options(5), ...
  const operators = sg.tables(3, 'SubGraph.operators').map((o, index) => {
    const opcodeIndex = o.u32(0, 0);
    if (opcodeIndex >= opcodes.length) throw new Error(`tflite: operator ${index} uses opcode ${opcodeIndex} of ${opcodes.length}`);
    const oc = opcodes[opcodeIndex];
    const what = `operator ${index} (${oc.name})`;
    const ins = (o.intVector(1) ?? []).map((i) => checkIndex(i, `${what} input`));
    const outs = (o.intVector(2) ?? []).map((i) => checkIndex(i, `${what} output`));
    const optType = o.u8(3, 0);
    let optionsType = null;
    let options = {};
    if (optType !== 0) {
      const reader = OPTION_READERS[optType];
      if (reader) {
        optionsType = reader[0];
        const table = o.subtable(4, `${what} options`);
        options = table ? reader[1](table) : {};
      } else {
        optionsType = `BuiltinOptions_${optType}`;
      }
    }
    return { index, op: oc.name, code: oc.code, version: oc.version, custom: oc.custom, inputs: ins, outputs: outs, optionsType, options };
  });
  return { version, description, tensors, inputs, outputs, operators };
}
