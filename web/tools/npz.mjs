// npz.mjs: numpy .npz archives written from JavaScript: a ZIP of "<name>.npy" members, stored
// (uncompressed), the layout np.savez writes and np.load / hawor's io/npz.hpp read.
//
// ZIP layout (PKWARE APPNOTE 4.3): per member a local file header (signature 0x04034b50,
// version 20, no flags, method 0 = stored, DOS date 1980-01-01, CRC-32, sizes, name), then the
// bytes; then a central directory entry per member (0x02014b50, same fields plus the offset of
// its local header); then the end-of-central-directory record (0x06054b50). Integers are
// little-endian. No ZIP64: every offset and size must stay below 4 GiB (checked).

import { encodeNpy, encodeNpyFloat32 } from './npy.mjs';

let crcTable = null;

/** CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320) of a byte array, as ZIP stores it. */
export function crc32(bytes) {
  if (!crcTable) {
    crcTable = new Uint32Array(256);
    for (let n = 0; n < 256; ++n) {
      let c = n;
      for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
      crcTable[n] = c >>> 0;
    }
  }
  let c = 0xffffffff;
  for (let i = 0; i < bytes.length; ++i) c = crcTable[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

const DOS_DATE_1980 = 0x21; // 1980-01-01 (day 1, month 1, year 0); time 00:00:00 = 0

/** A stored ZIP archive of `files`: [{name (string), bytes (Uint8Array)}], in order. */
export function encodeStoredZip(files) {
  const enc = new TextEncoder();
  const entries = files.map(({ name, bytes }) => {
    if (typeof name !== 'string' || name.length === 0) throw new Error('zip: every member needs a name');
    if (!(bytes instanceof Uint8Array)) throw new Error(`zip: member '${name}': bytes must be a Uint8Array`);
    return { name: enc.encode(name), bytes, crc: crc32(bytes) };
  });
  let localSize = 0;
  for (const e of entries) localSize += 30 + e.name.length + e.bytes.length;
  let centralSize = 0;
  for (const e of entries) centralSize += 46 + e.name.length;
  const total = localSize + centralSize + 22;
  if (localSize + centralSize > 0xffffffff || entries.length > 0xffff) throw new Error('zip: archive needs ZIP64 (over 4 GiB or 65535 members)');
  const out = new Uint8Array(total);
  const view = new DataView(out.buffer);
  let pos = 0;
  const u16 = (v) => { view.setUint16(pos, v, true); pos += 2; };
  const u32 = (v) => { view.setUint32(pos, v >>> 0, true); pos += 4; };
  for (const e of entries) {
    e.offset = pos;
    u32(0x04034b50); u16(20); u16(0); u16(0); u16(0); u16(DOS_DATE_1980);
    u32(e.crc); u32(e.bytes.length); u32(e.bytes.length); u16(e.name.length); u16(0);
    out.set(e.name, pos); pos += e.name.length;
    out.set(e.bytes, pos); pos += e.bytes.length;
  }
  const centralStart = pos;
  for (const e of entries) {
    u32(0x02014b50); u16(20); u16(20); u16(0); u16(0); u16(0); u16(DOS_DATE_1980);
    u32(e.crc); u32(e.bytes.length); u32(e.bytes.length); u16(e.name.length);
    u16(0); u16(0); u16(0); u16(0); u32(0); u32(e.offset);
    out.set(e.name, pos); pos += e.name.length;
  }
  const centralBytes = pos - centralStart;
  u32(0x06054b50); u16(0); u16(0); u16(entries.length); u16(entries.length);
  u32(centralBytes); u32(centralStart); u16(0);
  return out;
}

/** An .npz of typed arrays: `arrays` is [[name, {shape, data, bool?}], ...] or a Map (dtypes as
 *  encodeNpy in npy.mjs). */
export function encodeNpz(arrays) {
  const list = arrays instanceof Map ? [...arrays.entries()] : arrays;
  return encodeStoredZip(list.map(([name, a]) => ({ name: `${name}.npy`, bytes: encodeNpy(a.data, a.shape, { bool: !!a.bool }) })));
}

/** An .npz of float32 arrays: `arrays` is [[name, {shape, data: Float32Array}], ...] or a Map. */
export function encodeNpzFloat32(arrays) {
  const list = arrays instanceof Map ? [...arrays.entries()] : arrays;
  return encodeStoredZip(list.map(([name, a]) => ({ name: `${name}.npy`, bytes: encodeNpyFloat32(a.data, a.shape) })));
}
