//! The cell capacities a host program picks from at start-up (issue 24).
//!
//! The core holds its grids in fixed-capacity arrays: every map-sized structure is generic
//! over its capacity `N` \[cells\] (const generics, no allocation). A program on a host does
//! not know the map before it starts, so it compiles the mission for a short ladder of
//! capacities, [`CELL_TIERS`], and picks the smallest one that holds the map, in one place:
//! [`with_cell_capacity!`](crate::with_cell_capacity). Memory then follows the map (within a
//! factor of 4, the ladder's step; untouched pages of the zero-filled arrays are never
//! resident), and a map beyond [`MAX_CELLS`] is refused with the limit named.
//!
//! The ladder is short because each tier compiles the whole mission again (the release build
//! time is in `docs/benchmarks.md`). Steps of 4x from 2^16 cells: 256 x 256 (the built-in
//! lab and house at 0.1 m), 512 x 512, 1024 x 1024 (a 100 m x 100 m floor at 0.1 m, or
//! 50 m x 50 m at 0.05 m) and 2048 x 2048 (a 200 m square at 0.1 m).
//!
//! A build for a small PC can pin one capacity with the cargo feature `fixed-capacity`: every
//! tier is then [`FIXED_CELLS`] (one copy of the mission is compiled) and bigger maps are
//! refused.

/// The capacities \[cells\] a host program chooses from, smallest first.
#[cfg(not(feature = "fixed-capacity"))]
pub const CELL_TIERS: [usize; 4] = [1 << 16, 1 << 18, 1 << 20, 1 << 22];

/// The capacities \[cells\] a host program chooses from: with the feature `fixed-capacity`,
/// [`FIXED_CELLS`] only.
#[cfg(feature = "fixed-capacity")]
pub const CELL_TIERS: [usize; 4] = [FIXED_CELLS; 4];

/// The one capacity of a `fixed-capacity` build, and the capacity of the simulator's
/// fixed-size conveniences (tests, examples) \[cells\]: 512 x 512.
pub const FIXED_CELLS: usize = 1 << 18;

/// The largest map a program holds \[cells\].
pub const MAX_CELLS: usize = CELL_TIERS[CELL_TIERS.len() - 1];

/// The index in [`CELL_TIERS`] of the smallest capacity that holds `cells` cells, or `None`
/// beyond [`MAX_CELLS`].
pub fn tier(cells: usize) -> Option<usize> {
    CELL_TIERS.iter().position(|&t| cells <= t)
}

/// The smallest capacity of [`CELL_TIERS`] that holds `cells` cells, or `None` beyond
/// [`MAX_CELLS`].
pub fn capacity_for(cells: usize) -> Option<usize> {
    tier(cells).map(|i| CELL_TIERS[i])
}

/// Evaluates `body` with the const `N` set to the smallest capacity of
/// [`CELL_TIERS`](crate::capacity::CELL_TIERS) that holds `cells`: `Some(body)`, or `None`
/// when the map is beyond [`MAX_CELLS`](crate::capacity::MAX_CELLS). The one place a host
/// program turns a map's size into a capacity:
///
/// ```
/// // A program's generic entry point, e.g. one that builds `SharedMap::<N>` and runs.
/// fn run<const N: usize>(cells: usize) -> usize {
///     assert!(cells <= N);
///     N
/// }
/// let cells = 240 * 240;
/// let n = papillon::with_cell_capacity!(cells, N => run::<N>(cells)).unwrap();
/// assert_eq!(n, papillon::capacity::CELL_TIERS[0]);
/// assert_eq!(papillon::with_cell_capacity!(usize::MAX, N => run::<N>(0)), None);
/// ```
#[macro_export]
macro_rules! with_cell_capacity {
    ($cells:expr, $n:ident => $body:expr) => {
        match $crate::capacity::tier($cells) {
            ::core::option::Option::Some(0) => {
                const $n: usize = $crate::capacity::CELL_TIERS[0];
                ::core::option::Option::Some($body)
            }
            ::core::option::Option::Some(1) => {
                const $n: usize = $crate::capacity::CELL_TIERS[1];
                ::core::option::Option::Some($body)
            }
            ::core::option::Option::Some(2) => {
                const $n: usize = $crate::capacity::CELL_TIERS[2];
                ::core::option::Option::Some($body)
            }
            ::core::option::Option::Some(_) => {
                const $n: usize = $crate::capacity::CELL_TIERS[3];
                ::core::option::Option::Some($body)
            }
            ::core::option::Option::None => ::core::option::Option::None,
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_tier_that_holds_the_map_is_chosen() {
        let sizes = [0, 1, 240 * 240, 1000 * 1000, 1920 * 1920, MAX_CELLS];
        for cells in sizes.into_iter().filter(|&c| c <= MAX_CELLS) {
            let i = tier(cells).unwrap();
            assert!(CELL_TIERS[i] >= cells, "{cells}");
            if i > 0 {
                assert!(
                    CELL_TIERS[i - 1] < cells,
                    "{cells} fits the smaller tier {}",
                    CELL_TIERS[i - 1]
                );
            }
            let n = crate::with_cell_capacity!(cells, N => N).unwrap();
            assert_eq!(n, CELL_TIERS[i]);
        }
        assert_eq!(tier(MAX_CELLS + 1), None);
        assert_eq!(crate::with_cell_capacity!(MAX_CELLS + 1, N => N), None);
    }

    #[test]
    fn the_ladder_grows_and_holds_a_hundred_metre_floor() {
        assert!(CELL_TIERS.windows(2).all(|w| w[0] <= w[1]));
        #[cfg(not(feature = "fixed-capacity"))]
        assert!(capacity_for(1000 * 1000).is_some());
    }
}
