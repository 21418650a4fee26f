//! Per-cell clearance of a world: the chessboard (Chebyshev) distance, in cells, from each
//! cell to the nearest blocked cell, cells outside the grid counting as blocked.
//!
//! Computed by the two-pass sequential distance transform of Rosenfeld & Pfaltz ("Sequential
//! operations in digital picture processing", J. ACM 13(4), 1966): a forward raster pass takes
//! the minimum over the already-visited half of the 8-neighbourhood plus one, a backward pass
//! the other half; with unit weights on all eight neighbours the result is the exact chessboard
//! distance. Distances are capped at [`Clearance::MAX`] (a cap only makes a clearance smaller,
//! which every user reads as "no more than this many cells are known to be free").
//!
//! Users ask "is any blocked cell (or the grid's edge) within `m` cells of this one along
//! each axis?": no when the clearance is greater than `m`. The simulator's collision check and
//! laser use it to skip work in open space without changing any result.

/// Chessboard distance to the nearest blocked cell, per cell, in flat-index order.
#[derive(Clone, Debug)]
pub struct Clearance {
    width: usize,
    cells: Vec<u8>,
}

impl Clearance {
    /// The largest clearance stored (farther cells hold this value).
    pub const MAX: u8 = u8::MAX;

    /// The clearance of a `width` x (`blocked.len() / width`) world.
    pub fn new(width: usize, blocked: &[bool]) -> Self {
        let height = blocked.len().checked_div(width).unwrap_or(0);
        let mut d: Vec<u8> = blocked
            .iter()
            .map(|&b| if b { 0 } else { Self::MAX })
            .collect();
        // A neighbour outside the grid is blocked: distance 0.
        let at = |d: &[u8], col: isize, row: isize| -> u8 {
            if col < 0 || row < 0 || col >= width as isize || row >= height as isize {
                0
            } else {
                d[row as usize * width + col as usize]
            }
        };
        for row in 0..height as isize {
            for col in 0..width as isize {
                let i = row as usize * width + col as usize;
                if d[i] == 0 {
                    continue;
                }
                let m = at(&d, col - 1, row)
                    .min(at(&d, col - 1, row - 1))
                    .min(at(&d, col, row - 1))
                    .min(at(&d, col + 1, row - 1));
                d[i] = d[i].min(m.saturating_add(1));
            }
        }
        for row in (0..height as isize).rev() {
            for col in (0..width as isize).rev() {
                let i = row as usize * width + col as usize;
                if d[i] == 0 {
                    continue;
                }
                let m = at(&d, col + 1, row)
                    .min(at(&d, col + 1, row + 1))
                    .min(at(&d, col, row + 1))
                    .min(at(&d, col - 1, row + 1));
                d[i] = d[i].min(m.saturating_add(1));
            }
        }
        Self { width, cells: d }
    }

    /// The clearance of the cell at flat index `index` (panics past the cell count).
    #[inline]
    pub fn at_index(&self, index: usize) -> u8 {
        self.cells[index]
    }

    /// The grid's width \[cells\].
    pub fn width(&self) -> usize {
        self.width
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::random;

    /// The definition, cell by cell.
    fn brute(width: usize, blocked: &[bool]) -> Vec<u8> {
        let height = blocked.len() / width;
        let mut out = vec![0u8; blocked.len()];
        for row in 0..height as i64 {
            for col in 0..width as i64 {
                // The grid's edge: the nearest outside cell.
                let mut best = (col + 1)
                    .min(row + 1)
                    .min(width as i64 - col)
                    .min(height as i64 - row);
                for (j, &b) in blocked.iter().enumerate() {
                    if b {
                        let (c, r) = ((j % width) as i64, (j / width) as i64);
                        best = best.min((c - col).abs().max((r - row).abs()));
                    }
                }
                out[row as usize * width + col as usize] = best.min(255) as u8;
            }
        }
        out
    }

    #[test]
    fn matches_the_chessboard_distance_on_random_worlds() {
        let mut rng = random::seeded(7);
        for case in 0..60 {
            let width = 1 + (random::range_f32(&mut rng, 0.0, 30.0) as usize);
            let height = 1 + (random::range_f32(&mut rng, 0.0, 30.0) as usize);
            let density = random::range_f32(&mut rng, 0.0, 0.2);
            let blocked: Vec<bool> = (0..width * height)
                .map(|_| random::range_f32(&mut rng, 0.0, 1.0) < density)
                .collect();
            let c = Clearance::new(width, &blocked);
            assert_eq!(
                c.cells,
                brute(width, &blocked),
                "case {case}: {width} x {height}"
            );
        }
    }

    #[test]
    fn far_cells_are_capped() {
        let width = 600;
        let blocked = vec![false; width * width];
        let c = Clearance::new(width, &blocked);
        assert_eq!(c.at_index(0), 1, "next to the edge");
        assert_eq!(c.at_index(300 * width + 300), Clearance::MAX);
    }
}
