//! The uniform cell grid, as the runtime sees it.
//!
//! Input: a position (x, y) in the scene's local frame (metres, relative to the scene origin).
//! Output: the id of the cell holding it, row-major from the grid's minimum corner.
//! Invariants: cells are half-open `[x0, x0 + size)`; positions outside the grid, and NaN, map to
//! `None`; the id of cell (i, j) is `j * nx + i`.

/// Index of a view cell in a grid, row-major.
pub type CellId = u32;

/// A uniform grid of square view cells over the local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridDescriptor {
    /// Local x of the grid's minimum corner, metres.
    pub min_x: f64,
    /// Local y of the grid's minimum corner, metres.
    pub min_y: f64,
    /// Side of a cell, metres. Positive and finite.
    pub cell_size: f64,
    /// Number of columns.
    pub nx: u32,
    /// Number of rows.
    pub ny: u32,
}

impl GridDescriptor {
    /// Number of cells.
    pub fn cell_count(&self) -> u64 {
        self.nx as u64 * self.ny as u64
    }

    /// The cell holding local position (x, y), or `None` outside the grid.
    pub fn cell_at(&self, x: f64, y: f64) -> Option<CellId> {
        let fx = (x - self.min_x) / self.cell_size;
        let fy = (y - self.min_y) / self.cell_size;
        // Written so that NaN fails every comparison and is rejected.
        let inside = fx >= 0.0 && fy >= 0.0 && fx < self.nx as f64 && fy < self.ny as f64;
        if !inside {
            return None;
        }
        let (i, j) = (fx as u32, fy as u32);
        Some(j * self.nx + i)
    }

    /// Local rectangle `[x0, y0, x1, y1]` of a cell, or `None` for an id outside the grid.
    pub fn cell_rect(&self, id: CellId) -> Option<[f64; 4]> {
        if self.nx == 0 || id as u64 >= self.cell_count() {
            return None;
        }
        let (i, j) = (id % self.nx, id / self.nx);
        let x0 = self.min_x + i as f64 * self.cell_size;
        let y0 = self.min_y + j as f64 * self.cell_size;
        Some([x0, y0, x0 + self.cell_size, y0 + self.cell_size])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: GridDescriptor = GridDescriptor {
        min_x: -50.0,
        min_y: 0.0,
        cell_size: 100.0,
        nx: 3,
        ny: 2,
    };

    #[test]
    fn cell_at_is_row_major_and_half_open() {
        assert_eq!(G.cell_at(-50.0, 0.0), Some(0));
        assert_eq!(G.cell_at(49.999, 0.0), Some(0));
        assert_eq!(G.cell_at(50.0, 0.0), Some(1));
        assert_eq!(G.cell_at(249.9, 199.9), Some(5));
        assert_eq!(G.cell_at(250.0, 10.0), None);
        assert_eq!(G.cell_at(0.0, 200.0), None);
        assert_eq!(G.cell_at(-50.1, 10.0), None);
        assert_eq!(G.cell_at(f64::NAN, 10.0), None);
        assert_eq!(G.cell_at(0.0, f64::INFINITY), None);
    }

    #[test]
    fn cell_rect_inverts_cell_at() {
        for id in 0..G.cell_count() as u32 {
            let [x0, y0, x1, y1] = G.cell_rect(id).unwrap();
            assert_eq!(G.cell_at((x0 + x1) / 2.0, (y0 + y1) / 2.0), Some(id));
        }
        assert_eq!(G.cell_rect(6), None);
    }
}
