// @ts-check
/**
 * CRC-32 (ISO-HDLC, as zlib and PNG): reflected polynomial 0xEDB88320, initial value and final
 * XOR 0xFFFFFFFF (FORMAT.md section 7). The check value of "123456789" is 0xCBF43926.
 */

const TABLE = new Uint32Array(256);
for (let i = 0; i < 256; i++) {
  let c = i;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  TABLE[i] = c >>> 0;
}

/**
 * Feeds `bytes[start..end)` into the running state `c` (start with 0xFFFFFFFF).
 * @param {number} c
 * @param {Uint8Array} bytes
 * @param {number} [start]
 * @param {number} [end]
 */
export function crcUpdate(c, bytes, start = 0, end = bytes.length) {
  for (let i = start; i < end; i++) c = TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return c >>> 0;
}

/**
 * CRC-32 of `bytes[start..end)`.
 * @param {Uint8Array} bytes
 * @param {number} [start]
 * @param {number} [end]
 */
export function crc32(bytes, start = 0, end = bytes.length) {
  return (crcUpdate(0xffffffff, bytes, start, end) ^ 0xffffffff) >>> 0;
}
