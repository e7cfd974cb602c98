// npy.mjs: NumPy .npy files, C order: float64/32, int32, uint8 and bool written (format 1.0); float32/64, int32/64,
// uint8 and bool read (formats 1.0 to 3.0).
//
// Layout (numpy's format spec): the magic "\x93NUMPY", a major and a minor version byte, the
// header length (uint16 little-endian in 1.0, uint32 in 2.0 / 3.0), the header (an ASCII
// Python dict literal {'descr', 'fortran_order', 'shape'} padded with spaces and ended by
// '\n' so that the data starts at a multiple of 64 bytes), then the raw array data.

const MAGIC = [0x93, 0x4e, 0x55, 0x4d, 0x50, 0x59]; // \x93 N U M P Y

function littleEndian() {
  return new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;
}

const DTYPES = new Map([
  [Float64Array, '<f8'], [Float32Array, '<f4'], [Int32Array, '<i4'], [Uint8Array, '|u1'],
]);

/** A .npy file (format 1.0, C order) holding the typed array `data` (Float64Array '<f8',
 *  Float32Array '<f4', Int32Array '<i4', Uint8Array '|u1') with the given shape; bool: true
 *  stores a Uint8Array as '|b1'. */
export function encodeNpy(data, shape, { bool = false } = {}) {
  const descr = bool && data instanceof Uint8Array ? '|b1' : DTYPES.get(data?.constructor);
  if (!descr) throw new Error(`npy: unsupported array type ${data?.constructor?.name}`);
  if (!Array.isArray(shape) || shape.some((d) => !Number.isSafeInteger(d) || d < 0)) throw new Error('npy: shape must be non-negative integers');
  const count = shape.reduce((a, b) => a * b, 1);
  if (count !== data.length) throw new Error(`npy: ${data.length} values for shape (${shape.join(', ')})`);
  if (!littleEndian()) throw new Error('npy: big-endian platform');
  const shapeText = shape.length === 1 ? `(${shape[0]},)` : `(${shape.join(', ')})`;
  let header = `{'descr': '${descr}', 'fortran_order': False, 'shape': ${shapeText}, }`;
  const fixed = MAGIC.length + 2 + 2; // magic, version, header length
  const total = Math.ceil((fixed + header.length + 1) / 64) * 64;
  header = header.padEnd(total - fixed - 1, ' ') + '\n';
  if (header.length > 0xffff) throw new Error('npy: header too long for format 1.0');
  const out = new Uint8Array(total + data.byteLength);
  out.set(MAGIC, 0);
  out[6] = 1; // major version
  out[7] = 0; // minor version
  out[8] = header.length & 0xff;
  out[9] = header.length >> 8;
  for (let i = 0; i < header.length; ++i) out[fixed + i] = header.charCodeAt(i);
  out.set(new Uint8Array(data.buffer, data.byteOffset, data.byteLength), total);
  return out;
}

/** A .npy file holding `data` (Float32Array) as float32 little-endian with the given shape. */
export function encodeNpyFloat32(data, shape) {
  if (!(data instanceof Float32Array)) throw new Error('npy: data must be a Float32Array');
  return encodeNpy(data, shape);
}

/** Parses a .npy file: returns {shape, data}, C order, data a Float32Array ('<f4'),
 *  Float64Array ('<f8'), Int32Array ('<i4'), BigInt64Array ('<i8') or Uint8Array ('|u1',
 *  '|b1'). Throws on anything else. */
export function decodeNpy(bytes) {
  if (!(bytes instanceof Uint8Array)) throw new Error('npy: expected a Uint8Array');
  if (bytes.length < 10 || MAGIC.some((b, i) => bytes[i] !== b)) throw new Error('npy: not a .npy file (bad magic)');
  const major = bytes[6];
  let headerLen;
  let start;
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (major === 1) {
    headerLen = view.getUint16(8, true);
    start = 10;
  } else if (major === 2 || major === 3) {
    if (bytes.length < 12) throw new Error('npy: truncated header');
    headerLen = view.getUint32(8, true);
    start = 12;
  } else {
    throw new Error(`npy: unsupported format version ${major}`);
  }
  if (start + headerLen > bytes.length) throw new Error('npy: truncated header');
  const header = new TextDecoder('latin1').decode(bytes.subarray(start, start + headerLen));
  const descr = /'descr'\s*:\s*'([^']*)'/.exec(header);
  const fortran = /'fortran_order'\s*:\s*(True|False)/.exec(header);
  const shapeMatch = /'shape'\s*:\s*\(([^)]*)\)/.exec(header);
  if (!descr || !fortran || !shapeMatch) throw new Error(`npy: cannot parse header ${JSON.stringify(header.trim())}`);
  if (fortran[1] !== 'False') throw new Error('npy: Fortran-order arrays are not supported');
  const shape = shapeMatch[1].split(',').map((s) => s.trim()).filter((s) => s.length > 0).map((s) => {
    const n = Number(s.replace(/L$/, ''));
    if (!Number.isSafeInteger(n) || n < 0) throw new Error(`npy: bad dimension '${s}'`);
    return n;
  });
  const count = shape.reduce((a, b) => a * b, 1);
  const dataStart = start + headerLen;
  let size;
  let Type;
  const types = { '<f4': Float32Array, '<f8': Float64Array, '<i4': Int32Array, '<i8': BigInt64Array, '|u1': Uint8Array, '|b1': Uint8Array };
  Type = types[descr[1]];
  if (!Type) throw new Error(`npy: unsupported dtype '${descr[1]}' (one of ${Object.keys(types).join(', ')})`);
  size = Type.BYTES_PER_ELEMENT;
  if (bytes.length - dataStart < count * size) throw new Error(`npy: truncated data (${bytes.length - dataStart} bytes for ${count} values)`);
  if (!littleEndian()) throw new Error('npy: big-endian platform');
  // an aligned copy; Uint8Array's slice, as a node Buffer's own slice() does not copy
  const copy = Uint8Array.prototype.slice.call(bytes, dataStart, dataStart + count * size);
  return { shape, data: new Type(copy.buffer, 0, count) };
}
