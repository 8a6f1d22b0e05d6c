// @ts-check
/**
 * vocc's runtime for JavaScript: the store file, cell blobs and the frame of docs/FORMAT.md
 * (2.0 with its minor 2.1, and 1.0 still read), the cell at a position, and a cell's potentially visible set.
 * ES modules, no dependencies; the API is described in docs/EMBEDDING.md and index.d.ts.
 */

export { FormatError } from './errors.js';
export { crc32 } from './crc.js';
export {
  Frame, QPoint, QVo, decodeFrame, encodeFrame, validateFrame, powU8, standOf,
  FRAME_LEN, HEIGHT_LEVELS, HEIGHT_LEVELS_V1, MAX_VOS_PER_CELL,
} from './frame.js';
export { Store, decodeBlob, VERSIONS, KNOWN_FLAGS, HEADER_LEN, BLOB_MIN_LEN, SKIPPED, RISE_BASE } from './format.js';
export { PreparedVo, MARGIN_M, hides, hypot } from './occlusion.js';
export { BoxTree, pvs, f32Below, LEAF_SIZE } from './culler.js';
