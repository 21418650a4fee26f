//! A candidate's evaluation: whether it can be driven and how it scores. Shared by the
//! objective that computes evaluations and the memo that remembers them.

/// Fitness of an infeasible or blocked candidate: worse than any feasible one (those lie in
/// `[-1, 0]`).
pub const WORST_FITNESS: f32 = 1.0;

/// Whether a candidate can be driven. All zeros is [`CandidateStatus::Feasible`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Zeroable)]
#[repr(u8)]
pub enum CandidateStatus {
    /// Reachable and within the battery.
    Feasible,
    /// A target lies outside the grid.
    OutOfBounds,
    /// A target lies on an Occupied or inflated cell.
    Blocked,
    /// No path reaches a target.
    Unreachable,
    /// The path costs more than the battery minus the reserve.
    OverBudget,
    /// The path does not fit the waypoint, leg or viewpoint capacities.
    TooLong,
}

/// A candidate's evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Evaluation {
    /// Feasibility.
    pub status: CandidateStatus,
    /// Unknown cells predicted to become known \[cells\] (0 unless feasible).
    pub gain_cells: u32,
    /// Energy of the path \[steps\] (as far as it was planned).
    pub energy_steps: f32,
    /// Length of the waypoint polyline \[m\].
    pub path_length_m: f32,
    /// Fitness for the optimizers (minimised): [`WORST_FITNESS`] unless feasible, else in
    /// `[-1, 0]`.
    pub fitness: f32,
}
