// Types of vocc's JavaScript runtime (js/src/index.js). docs/EMBEDDING.md describes its use;
// docs/FORMAT.md the bytes it reads.

/** Why bytes were refused: the Rust `FormatError`'s variant name, fields and message. */
export class FormatError extends Error {
  constructor(kind: string, fields?: Record<string, unknown>);
  /** `Truncated`, `TrailingBytes`, `BadMagic`, `UnsupportedVersion`, `UnknownFlags`, `BadFrame`,
   * `Checksum`, `BadIndexByte`, `BlockOffset`, `PayloadLength`, `DegenerateVo`, `BadRise`,
   * `NonCanonicalVo`, `CrsNotUtf8` or `CellOutOfGrid` (`ReservedVoBit` is a 2.0 reader's
   * refusal of a 2.1 deep VO: this reader reads bit 47 and never throws it). */
  kind: string;
  /** The variant's fields: offsets (from the start of the file or blob), values, rules. */
  fields: Record<string, any>;
}

/** CRC-32 (ISO-HDLC) of `bytes[start..end)`. */
export function crc32(bytes: Uint8Array, start?: number, end?: number): number;

export const FRAME_LEN: 112;
export const HEIGHT_LEVELS: 32;
export const HEIGHT_LEVELS_V1: 16;
export const MAX_VOS_PER_CELL: 10;
export const HEADER_LEN: 136;
export const BLOB_MIN_LEN: 14;
export const SKIPPED: 255;
/** Index values `RISE_BASE + n` (`n` in 1..=10) announce `n` VOs with a rise byte (2.1). */
export const RISE_BASE: 10;
/** Store flag bits this reader knows (none: every bit is reserved in 1.0 and 2.0). */
export const KNOWN_FLAGS: number;
/** Rule 3's safety margin, metres. */
export const MARGIN_M: number;
/** Most boxes in a leaf of the box tree. */
export const LEAF_SIZE: number;

/** A cell as rule 3 sees it: rectangle `[x0, y0, x1, y1]` and eye heights, local frame. */
export interface CellView { rect: number[]; e0: number; e1: number }
/** A VO as geometry: segment `a`–`b` (local) standing from `g` (the cell's ground, or
 * `ground_z0` for a deep VO) to `h`. */
export interface VoGeom { a: number[]; b: number[]; g: number; h: number }

/** A quantized endpoint: `centre + (x - 256, y - 256) * quantum * 2^e`. */
export class QPoint {
  constructor(e: number, x: number, y: number);
  e: number;
  x: number;
  y: number;
  isCanonical(): boolean;
  steps(): number[];
  offset(quantum: number): number[];
}

/** One stored VO: two endpoints, a height level (0..32; 0..16 in 1.0) and the deep flag. */
export class QVo {
  constructor(a: QPoint, b: QPoint, level: number, deep?: boolean);
  a: QPoint;
  b: QPoint;
  level: number;
  /** Format 2.1 (bit 47): the VO stands from `ground_z0`, not from its cell's ground. */
  deep: boolean;
  isCanonical(): boolean;
  isDegenerate(): boolean;
}

export interface FrameFields {
  origin: number[]; minX: number; minY: number; cellSize: number; nx: number; ny: number;
  quantum: number; eyeLo: number; eyeHi: number; groundZ0: number; groundStep: number;
  h0: number; hRatio: number;
}

/** The frame (FORMAT.md 4): origin, grid, quantization, vertical frame. */
export class Frame implements FrameFields {
  constructor(fields: FrameFields);
  origin: number[]; minX: number; minY: number; cellSize: number; nx: number; ny: number;
  quantum: number; eyeLo: number; eyeHi: number; groundZ0: number; groundStep: number;
  h0: number; hRatio: number;
  cellCount(): number;
  perCellGround(): boolean;
  groundZ(level: number): number;
  /** The top eye of a cell standing on `stand`: `groundZ(level) + rise * groundStep + eyeHi`. */
  topEye(stand: Stand): number;
  voTop(e1: number, level: number): number;
  /** The cell at a local position, or null outside the grid (and for NaN). */
  cellAt(x: number, y: number): number | null;
  /** The cell at a world position, or null. */
  cellAtWorld(x: number, y: number): number | null;
  cellRect(id: number): number[] | null;
  cellCentre(id: number): number[] | null;
  /** The cell's rectangle and eyes; give it the cell's record (its rise raises the top eye). */
  cellView(id: number, stand: Stand): CellView | null;
  /** A stored VO as geometry; give it the cell's record (its rise raises the VO's top). */
  dequantize(id: number, stand: Stand, q: QVo): VoGeom | null;
}

/** Where a cell stands: a bare ground level (rise 0), or a record's `ground` and `rise` (2.1). */
export type Stand = number | { ground: number; rise?: number };
/** `stand` as a level and a rise. */
export function standOf(stand: Stand): { level: number; rise: number };

/** Decodes and checks the 112 bytes of a frame (the `.frame` file beside blobs). */
export function decodeFrame(bytes: Uint8Array): Frame;
export function encodeFrame(frame: Frame): Uint8Array;
/** Frame rules F1..F12 (F12 at `topLevel`, default 31); throws `BadFrame`. */
export function validateFrame(frame: Frame, topLevel?: number): void;
/** `r^k` by binary powering, as the Rust runtime computes VO tops. */
export function powU8(r: number, k: number): number;

/** One cell's record: skipped, or a ground level, a rise (2.1: the top eye stands `rise` ground
 * steps higher; 0 in 2.0 and 1.0) and at most 10 VOs. */
export interface CellRecord { skipped: boolean; ground: number; rise: number; vos: QVo[] }

/** What differs between the majors read (1 and 2). */
export interface Version {
  major: number;
  voBytes: number;
  topLevel: number;
  sceneSection: boolean;
  decodeVo(bytes: Uint8Array, at: number): QVo;
  /** Whether index values 11..=20 (2.1, with ground bytes) are read. */
  rise: boolean;
}
export const VERSIONS: Record<number, Version>;

/** A store file (2.0, its minor 2.1, or 1.0), checked whole by `Store.parse`; keeps a reference to the bytes. */
export class Store {
  static parse(bytes: Uint8Array): Store;
  constructor(bytes: Uint8Array);
  readonly bytes: Uint8Array;
  readonly frame: Frame;
  readonly version: Version;
  readonly major: number;
  readonly minor: number;
  /** Objects the store was baked for (0: not recorded, and in 1.0). */
  readonly objects: number;
  /** The scene fingerprint (0n: not recorded). */
  readonly scene: bigint;
  /** The CRS name ('' : unknown). */
  readonly crs: string;
  readonly cellCount: number;
  readonly voBytes: number;
  cellBytes(id: number): number;
  /** A cell's record: reads at most 63 index bytes and the record. */
  cell(id: number): CellRecord;
  cellAt(x: number, y: number): number | null;
}

/** Decodes and checks a cell blob (2.0 and 2.1, or 1.0) against the frame of its store. */
export function decodeBlob(frame: Frame, bytes: Uint8Array): { id: number; record: CellRecord };

/** A VO prepared for the box tests of rule 3 against one cell. */
export class PreparedVo {
  constructor(view: CellView, vo: VoGeom);
  readonly usable: boolean;
  readonly heightsOk: boolean;
}
/** Whether a prepared VO hides box `[xmin, ymin, zmin, xmax, ymax, zmax]` (local). */
export function hides(view: CellView, vo: PreparedVo, box: ArrayLike<number>): boolean;
/** `hypot` with the bits of glibc's, which the Rust runtime uses (Math.hypot rounds otherwise). */
export function hypot(x: number, y: number): number;
/** `x` rounded down to an f32. */
export function f32Below(x: number): number;

/** The box tree over object boxes (six numbers per object), built once per scene. */
export class BoxTree {
  /** From world boxes: `local = world - origin` (the frame's origin). */
  static fromWorld(world: ArrayLike<number>, origin: number[]): BoxTree;
  /** From local boxes. */
  constructor(boxes: ArrayLike<number>);
  /** Number of objects, valid or not. */
  readonly length: number;
}

export interface PvsStats { vos: number; nodesTested: number; boxesTested: number }

/** The PVS of a cell: the ascending indices of the objects no VO of it hides (rule 3). */
export function pvs(frame: Frame, id: number, record: CellRecord, tree: BoxTree, stats?: PvsStats): Uint32Array;
