// @ts-check
/**
 * Why bytes were refused: the JavaScript form of the Rust `FormatError` (src/runtime/format/mod.rs).
 *
 * Input: a kind and its fields. Output: an `Error` whose `kind` and `fields` name the rule
 * broken and where (offsets from the start of the store file or blob), and whose `message` is
 * the text of the Rust error's `Display`, character for character (the tests compare them).
 * Invariant: one kind per variant the decoders return; a new rule is a new entry of MESSAGES.
 */

/** @param {number} n */
const hex32 = (n) => '0x' + (n >>> 0).toString(16).padStart(8, '0');

/** @type {Record<string, (f: any) => string>} */
const MESSAGES = {
  Truncated: (f) => `truncated: ${f.needed} bytes needed, ${f.got} given`,
  TrailingBytes: (f) => `trailing bytes: ${f.expected} bytes expected, ${f.got} given`,
  BadMagic: () => 'bad magic number: not a vocc store or blob',
  UnsupportedVersion: (f) =>
    `unsupported major version ${f.major} (this reader implements 1 and 2)`,
  UnknownFlags: (f) =>
    `unknown flags ${hex32(f.flags)} at offset 12 (every bit is reserved in versions 1.0 and 2.0)`,
  BadFrame: (f) => `bad frame: rule ${f.rule}`,
  Checksum: (f) => `checksum mismatch: stored ${hex32(f.stored)}, computed ${hex32(f.computed)}`,
  BadIndexByte: (f) =>
    `bad count ${f.value} for cell ${f.cell} at offset ${f.offset} (0..=10 VOs or 255 skipped)`,
  BlockOffset: (f) =>
    `block table entry ${f.block} is ${f.stored}, the counts before it give ${f.expected}`,
  PayloadLength: (f) => `payload_len is ${f.stored}, the counts give ${f.expected}`,
  DegenerateVo: (f) =>
    `VO ${f.vo} of cell ${f.cell} at offset ${f.offset} is degenerate (one grid point)`,
  // A 2.0 reader's refusal of a 2.1 deep VO; this reader (as Rust's) reads bit 47 and never
  // throws it.
  ReservedVoBit: (f) => `VO ${f.vo} of cell ${f.cell} at offset ${f.offset} sets the reserved bit 47`,
  NonCanonicalVo: (f) =>
    `VO ${f.vo} of cell ${f.cell} at offset ${f.offset}: endpoint ${f.endpoint} is not canonical (a smaller exponent holds it)`,
  CrsNotUtf8: (f) => `the CRS name is not UTF-8 (at offset ${f.offset})`,
  CellOutOfGrid: (f) => `cell ${f.id} is outside the grid of ${f.cells} cells`,
  BadRise: (f) =>
    `cell ${f.cell}'s rise ${f.rise} at offset ${f.offset} is 0 or takes its ground level ${f.ground} past 255`,
};

export class FormatError extends Error {
  /**
   * @param {string} kind the Rust variant's name, e.g. `Truncated`
   * @param {Record<string, any>} [fields] its fields, e.g. `{ needed: 136, got: 3 }`
   */
  constructor(kind, fields = {}) {
    const text = MESSAGES[kind];
    super(text ? text(fields) : kind);
    this.name = 'FormatError';
    /** @type {string} */
    this.kind = kind;
    /** @type {Record<string, any>} */
    this.fields = fields;
  }
}
