//! A 2-D pose graph and its least-squares solver: nodes are keyframe poses (map frame), edges
//! are measured relative poses between two nodes with their information (the inverse of their
//! covariance, diagonal, in the first node's frame).
//!
//! The solver is Gauss-Newton on the sum of squared edge errors, as in Grisetti, Kümmerle,
//! Stachniss & Burgard, *A tutorial on graph-based SLAM*, IEEE Intelligent Transportation
//! Systems Magazine 2(4), 2010, §IV: the error of edge `(i, j)` measuring `z` is
//! `e = t2v(Z⁻¹ (Xᵢ⁻¹ Xⱼ))`, its Jacobians `A = ∂e/∂xᵢ` and `B = ∂e/∂xⱼ` are the tutorial's
//! eq. (13), and each iteration solves `H Δx = -b` with `H = Σ Jᵀ Ω J`, `b = Σ Jᵀ Ω e`, the
//! first node held fixed (the gauge). `H` is never formed: it is sparse (one block per edge),
//! so the system is solved by conjugate gradients (Hestenes & Stiefel, *Methods of conjugate
//! gradients for solving linear systems*, J. Res. NBS 49(6), 1952), products `H v` taken edge
//! by edge, preconditioned by the inverses of `H`'s 3 x 3 diagonal blocks (block Jacobi, as
//! g2o's PCG solver: Kümmerle et al., *g2o*, ICRA 2011). Memory is the graph's own fixed
//! arrays (`K` nodes, `E` edges): no allocation; f64 throughout, deterministic.

use crate::geometry::Pose2;
use crate::math;

/// Why a node or edge was not added.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphError {
    /// The graph holds `capacity` nodes already.
    NodesFull {
        /// Nodes it holds at most.
        capacity: usize,
    },
    /// The graph holds `capacity` edges already.
    EdgesFull {
        /// Edges it holds at most.
        capacity: usize,
    },
    /// An edge names a node that does not exist, or the same node twice.
    BadEdge {
        /// The edge's first node.
        from: usize,
        /// Its second node.
        to: usize,
    },
    /// A pose, measurement or information is not finite, or an information is not positive.
    NotFinite,
}

impl core::fmt::Display for GraphError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NodesFull { capacity } => {
                write!(f, "pose graph: all {capacity} nodes in use")
            }
            Self::EdgesFull { capacity } => {
                write!(f, "pose graph: all {capacity} edges in use")
            }
            Self::BadEdge { from, to } => {
                write!(f, "pose graph: edge {from} -> {to} names a missing node")
            }
            Self::NotFinite => write!(
                f,
                "pose graph: a pose or measurement is not finite, or an information is not positive"
            ),
        }
    }
}

impl core::error::Error for GraphError {}

/// A measured relative pose between two nodes.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Zeroable)]
pub struct Edge {
    /// The node the measurement is expressed in.
    pub from: u16,
    /// The node measured.
    pub to: u16,
    /// `to`'s pose in `from`'s frame \[m, rad\].
    pub measured: Pose2,
    /// Information (inverse variance) of the measurement's x, y (in `from`'s frame, rotated
    /// by the measurement) and heading \[1/m², 1/m², 1/rad²\].
    pub information: [f32; 3],
}

/// What one optimisation did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Optimised {
    /// Gauss-Newton iterations run.
    pub iterations: u32,
    /// Conjugate-gradient steps run, all iterations together.
    pub cg_steps: u32,
    /// Weighted squared error before and after (`Σ eᵀ Ω e`).
    pub error_before: f64,
    /// ... after.
    pub error_after: f64,
    /// Largest move of a node's position \[m\] ...
    pub max_move_m: f32,
    /// ... and of its heading \[rad\].
    pub max_turn_rad: f32,
}

/// Per-edge working values of one iteration.
#[derive(Clone, Copy, Default, bytemuck::Zeroable)]
struct Linear {
    /// `∂e/∂xᵢ`, row-major 3 x 3.
    a: [f64; 9],
    /// The rotation part of `∂e/∂xⱼ` (its other entries are 0 and a 1 for the heading).
    r: [f64; 4],
    /// The error.
    e: [f64; 3],
}

/// A pose graph of at most `K` nodes and `E` edges, with the solver's working memory.
#[derive(bytemuck::Zeroable)]
pub struct PoseGraph<const K: usize, const E: usize> {
    nodes: [[f64; 3]; K],
    len: usize,
    edges: [Edge; E],
    edge_len: usize,
    lin: [Linear; E],
    /// Inverses of `H`'s diagonal blocks.
    block: [[f64; 9]; K],
    b: [[f64; 3]; K],
    dx: [[f64; 3]; K],
    res: [[f64; 3]; K],
    pre: [[f64; 3]; K],
    dir: [[f64; 3]; K],
    hdir: [[f64; 3]; K],
    /// Each node's move in this optimisation.
    moved: [[f64; 3]; K],
}

impl<const K: usize, const E: usize> core::fmt::Debug for PoseGraph<K, E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("PoseGraph")
            .field("nodes", &self.len)
            .field("edges", &self.edge_len)
            .finish_non_exhaustive()
    }
}

/// Row-major 3 x 3 times a 3-vector.
fn mul(m: &[f64; 9], v: &[f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

/// Transposed row-major 3 x 3 times a 3-vector.
fn mul_t(m: &[f64; 9], v: &[f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[3] * v[1] + m[6] * v[2],
        m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
        m[2] * v[0] + m[5] * v[1] + m[8] * v[2],
    ]
}

/// `B v` for `B = [[r, 0], [0, 1]]`.
fn mul_b(r: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    [r[0] * v[0] + r[1] * v[1], r[2] * v[0] + r[3] * v[1], v[2]]
}

/// `Bᵀ v`.
fn mul_bt(r: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    [r[0] * v[0] + r[2] * v[1], r[1] * v[0] + r[3] * v[1], v[2]]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn wrap(a: f64) -> f64 {
    let tau = core::f64::consts::TAU;
    let mut r = a - tau * libm::floor((a + core::f64::consts::PI) / tau);
    if r <= -core::f64::consts::PI {
        r += tau;
    }
    r
}

/// Inverse of a symmetric positive 3 x 3 (row-major); `None` when singular.
fn invert(m: &[f64; 9]) -> Option<[f64; 9]> {
    let c00 = m[4] * m[8] - m[5] * m[7];
    let c01 = m[5] * m[6] - m[3] * m[8];
    let c02 = m[3] * m[7] - m[4] * m[6];
    let det = m[0] * c00 + m[1] * c01 + m[2] * c02;
    if !(det.is_finite() && det.abs() > 1e-300) {
        return None;
    }
    let inv = 1.0 / det;
    Some([
        c00 * inv,
        (m[2] * m[7] - m[1] * m[8]) * inv,
        (m[1] * m[5] - m[2] * m[4]) * inv,
        c01 * inv,
        (m[0] * m[8] - m[2] * m[6]) * inv,
        (m[2] * m[3] - m[0] * m[5]) * inv,
        c02 * inv,
        (m[1] * m[6] - m[0] * m[7]) * inv,
        (m[0] * m[4] - m[1] * m[3]) * inv,
    ])
}

impl<const K: usize, const E: usize> Default for PoseGraph<K, E> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize, const E: usize> PoseGraph<K, E> {
    /// An empty graph (on the stack: for small `K` and `E`; a host boxes large ones zeroed).
    pub fn new() -> Self {
        bytemuck::Zeroable::zeroed()
    }

    /// Forgets every node and edge.
    pub fn clear(&mut self) {
        self.len = 0;
        self.edge_len = 0;
    }

    /// Nodes held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the graph has no node.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Edges held.
    pub fn edge_count(&self) -> usize {
        self.edge_len
    }

    /// The edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges[..self.edge_len]
    }

    /// Node `i`'s pose (map frame), `None` past the last node.
    pub fn pose(&self, i: usize) -> Option<Pose2> {
        (i < self.len).then(|| {
            let n = self.nodes[i];
            Pose2::new(n[0] as f32, n[1] as f32, n[2] as f32)
        })
    }

    /// Adds a node at `pose`; returns its index.
    pub fn add_node(&mut self, pose: Pose2) -> Result<usize, GraphError> {
        if !(pose.x.is_finite() && pose.y.is_finite() && pose.theta.is_finite()) {
            return Err(GraphError::NotFinite);
        }
        if self.len >= K {
            return Err(GraphError::NodesFull { capacity: K });
        }
        self.nodes[self.len] = [f64::from(pose.x), f64::from(pose.y), f64::from(pose.theta)];
        self.len += 1;
        Ok(self.len - 1)
    }

    /// Adds an edge between existing nodes.
    pub fn add_edge(&mut self, edge: Edge) -> Result<(), GraphError> {
        let (from, to) = (usize::from(edge.from), usize::from(edge.to));
        if from >= self.len || to >= self.len || from == to {
            return Err(GraphError::BadEdge { from, to });
        }
        let m = edge.measured;
        if !(m.x.is_finite()
            && m.y.is_finite()
            && m.theta.is_finite()
            && edge.information.iter().all(|w| w.is_finite() && *w > 0.0))
        {
            return Err(GraphError::NotFinite);
        }
        if self.edge_len >= E {
            return Err(GraphError::EdgesFull { capacity: E });
        }
        self.edges[self.edge_len] = edge;
        self.edge_len += 1;
        Ok(())
    }

    /// The error of edge `k` at the current poses and, when `lin`, its Jacobians.
    fn linearise(&mut self, k: usize) -> f64 {
        let edge = self.edges[k];
        let xi = self.nodes[usize::from(edge.from)];
        let xj = self.nodes[usize::from(edge.to)];
        let (si, ci) = (libm::sin(xi[2]), libm::cos(xi[2]));
        let z = edge.measured;
        let zt = f64::from(z.theta);
        let (sz, cz) = (libm::sin(zt), libm::cos(zt));
        let (dx, dy) = (xj[0] - xi[0], xj[1] - xi[1]);
        // Rᵢᵀ (tⱼ - tᵢ) and its derivative with respect to θᵢ.
        let (lx, ly) = (ci * dx + si * dy, -si * dx + ci * dy);
        let (gx, gy) = (-si * dx + ci * dy, -ci * dx - si * dy);
        // e = Rzᵀ (Rᵢᵀ (tⱼ - tᵢ) - tz), θⱼ - θᵢ - θz.
        let (ux, uy) = (lx - f64::from(z.x), ly - f64::from(z.y));
        let e = [
            cz * ux + sz * uy,
            -sz * ux + cz * uy,
            wrap(xj[2] - xi[2] - zt),
        ];
        // Rzᵀ Rᵢᵀ.
        let r = [
            cz * ci - sz * si,
            cz * si + sz * ci,
            -sz * ci - cz * si,
            -sz * si + cz * ci,
        ];
        let a = [
            -r[0],
            -r[1],
            cz * gx + sz * gy,
            -r[2],
            -r[3],
            -sz * gx + cz * gy,
            0.0,
            0.0,
            -1.0,
        ];
        self.lin[k] = Linear { a, r, e };
        let w = edge.information.map(f64::from);
        w[0] * e[0] * e[0] + w[1] * e[1] * e[1] + w[2] * e[2] * e[2]
    }

    /// Removes the last edge added (a closure found inconsistent after an optimisation).
    pub fn pop_edge(&mut self) -> Option<Edge> {
        self.edge_len = self.edge_len.checked_sub(1)?;
        Some(self.edges[self.edge_len])
    }

    /// Edge `k`'s weighted squared error `eᵀ Ω e` at the current poses (0 past the last).
    pub fn edge_error(&mut self, k: usize) -> f64 {
        if k < self.edge_len {
            self.linearise(k)
        } else {
            0.0
        }
    }

    /// The weighted squared error `Σ eᵀ Ω e` at the current poses.
    pub fn error(&mut self) -> f64 {
        (0..self.edge_len).map(|k| self.linearise(k)).sum()
    }

    /// `hdir = H dir` (node 0 held: its rows and columns are left out).
    fn product(&mut self) {
        for v in &mut self.hdir[..self.len] {
            *v = [0.0; 3];
        }
        for k in 0..self.edge_len {
            let edge = self.edges[k];
            let (i, j) = (usize::from(edge.from), usize::from(edge.to));
            let l = &self.lin[k];
            let vi = if i == 0 { [0.0; 3] } else { self.dir[i] };
            let vj = if j == 0 { [0.0; 3] } else { self.dir[j] };
            let av = mul(&l.a, &vi);
            let bv = mul_b(&l.r, &vj);
            let w = edge.information;
            let s = [
                f64::from(w[0]) * (av[0] + bv[0]),
                f64::from(w[1]) * (av[1] + bv[1]),
                f64::from(w[2]) * (av[2] + bv[2]),
            ];
            let hi = mul_t(&l.a, &s);
            let hj = mul_bt(&l.r, &s);
            for d in 0..3 {
                self.hdir[i][d] += hi[d];
                self.hdir[j][d] += hj[d];
            }
        }
        self.hdir[0] = [0.0; 3];
    }

    /// Runs at most `iterations` Gauss-Newton steps of at most `cg_steps` conjugate-gradient
    /// steps each, stopping when no node moves more than 0.1 mm or 0.0001 rad. Node 0 stays
    /// where it is.
    pub fn optimise(&mut self, iterations: u32, cg_steps: u32) -> Optimised {
        let n = self.len;
        let mut out = Optimised::default();
        if n < 2 || self.edge_len == 0 {
            return out;
        }
        for m in &mut self.moved[..n] {
            *m = [0.0; 3];
        }
        for it in 0..iterations {
            // Linearise; gradient b and the diagonal blocks of H.
            for v in &mut self.b[..n] {
                *v = [0.0; 3];
            }
            for m in &mut self.block[..n] {
                *m = [0.0; 9];
            }
            let mut err = 0.0;
            for k in 0..self.edge_len {
                err += self.linearise(k);
                let edge = self.edges[k];
                let (i, j) = (usize::from(edge.from), usize::from(edge.to));
                let l = self.lin[k];
                let w = edge.information.map(f64::from);
                let we = [w[0] * l.e[0], w[1] * l.e[1], w[2] * l.e[2]];
                let gi = mul_t(&l.a, &we);
                let gj = mul_bt(&l.r, &we);
                for d in 0..3 {
                    self.b[i][d] += gi[d];
                    self.b[j][d] += gj[d];
                }
                // Aᵀ Ω A and Bᵀ Ω B.
                let bm = [l.r[0], l.r[1], 0.0, l.r[2], l.r[3], 0.0, 0.0, 0.0, 1.0];
                let jtj = |m: &[f64; 9], r: usize, c: usize| {
                    w.iter()
                        .enumerate()
                        .map(|(q, wq)| m[q * 3 + r] * wq * m[q * 3 + c])
                        .sum::<f64>()
                };
                for r in 0..3 {
                    for c in 0..3 {
                        self.block[i][r * 3 + c] += jtj(&l.a, r, c);
                        self.block[j][r * 3 + c] += jtj(&bm, r, c);
                    }
                }
            }
            if it == 0 {
                out.error_before = err;
            }
            for m in &mut self.block[..n] {
                // A node no edge reaches keeps its pose: identity block, zero gradient.
                *m = invert(m).unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
            }
            self.b[0] = [0.0; 3];

            // Preconditioned conjugate gradients on H dx = -b, from dx = 0.
            let mut rz = 0.0;
            let mut r0 = 0.0;
            for i in 0..n {
                self.dx[i] = [0.0; 3];
                self.res[i] = [-self.b[i][0], -self.b[i][1], -self.b[i][2]];
                self.pre[i] = mul(&self.block[i], &self.res[i]);
                self.dir[i] = self.pre[i];
                rz += dot(&self.res[i], &self.pre[i]);
                r0 += dot(&self.res[i], &self.res[i]);
            }
            if r0 <= 0.0 || !r0.is_finite() {
                out.iterations = it + 1;
                break;
            }
            for _ in 0..cg_steps {
                self.product();
                let mut php = 0.0;
                for i in 0..n {
                    php += dot(&self.dir[i], &self.hdir[i]);
                }
                if php.is_nan() || php <= 0.0 {
                    break;
                }
                let alpha = rz / php;
                let mut rr = 0.0;
                for i in 0..n {
                    for d in 0..3 {
                        self.dx[i][d] += alpha * self.dir[i][d];
                        self.res[i][d] -= alpha * self.hdir[i][d];
                    }
                    rr += dot(&self.res[i], &self.res[i]);
                }
                out.cg_steps += 1;
                if rr <= 1e-20 * r0 {
                    break;
                }
                let mut rz_new = 0.0;
                for i in 0..n {
                    self.pre[i] = mul(&self.block[i], &self.res[i]);
                    rz_new += dot(&self.res[i], &self.pre[i]);
                }
                let beta = rz_new / rz;
                rz = rz_new;
                for i in 0..n {
                    for d in 0..3 {
                        self.dir[i][d] = self.pre[i][d] + beta * self.dir[i][d];
                    }
                }
            }
            let mut step = 0.0f64;
            for i in 1..n {
                let d = self.dx[i];
                if !(d[0].is_finite() && d[1].is_finite() && d[2].is_finite()) {
                    continue;
                }
                self.nodes[i][0] += d[0];
                self.nodes[i][1] += d[1];
                self.nodes[i][2] = wrap(self.nodes[i][2] + d[2]);
                for (m, d) in self.moved[i].iter_mut().zip(d) {
                    *m += d;
                }
                step = step.max(libm::hypot(d[0], d[1])).max(d[2].abs());
            }
            out.iterations = it + 1;
            if step < 1e-4 {
                break;
            }
        }
        out.error_after = self.error();
        for m in &self.moved[..n] {
            out.max_move_m = out.max_move_m.max(libm::hypot(m[0], m[1]) as f32);
            out.max_turn_rad = out.max_turn_rad.max(math::abs(wrap(m[2]) as f32));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The true poses of a 4 m square driven anticlockwise in 1 m steps, turning 90° at each
    /// corner: 17 nodes, the last back at the first.
    fn square() -> [Pose2; 17] {
        let mut out = [Pose2::default(); 17];
        let mut p = Pose2::new(1.0, 2.0, 0.3);
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = p;
            let turn = if k % 4 == 3 {
                core::f32::consts::FRAC_PI_2
            } else {
                0.0
            };
            p = p.compose(Pose2::new(1.0, 0.0, turn));
        }
        out
    }

    fn step_info() -> [f32; 3] {
        [1e4, 1e4, 1e4]
    }

    /// A graph over `truth` whose consecutive edges are `measure(k)` and whose nodes start
    /// dead-reckoned from them.
    fn chain(truth: &[Pose2], measure: impl Fn(usize) -> Pose2) -> PoseGraph<32, 64> {
        let mut g = PoseGraph::<32, 64>::new();
        let mut p = truth[0];
        g.add_node(p).unwrap();
        for k in 1..truth.len() {
            let z = measure(k);
            p = p.compose(z);
            g.add_node(p).unwrap();
            g.add_edge(Edge {
                from: (k - 1) as u16,
                to: k as u16,
                measured: z,
                information: step_info(),
            })
            .unwrap();
        }
        g
    }

    fn worst(g: &PoseGraph<32, 64>, truth: &[Pose2]) -> (f32, f32) {
        let mut out = (0.0f32, 0.0f32);
        for (k, t) in truth.iter().enumerate() {
            let p = g.pose(k).unwrap();
            out.0 = out.0.max(p.position().distance(t.position()));
            out.1 = out
                .1
                .max(crate::geometry::normalize_angle(p.theta - t.theta).abs());
        }
        out
    }

    #[test]
    fn exact_edges_bring_a_drifted_square_back_to_the_truth() {
        let truth = square();
        // Exact edges, but the nodes start from a dead reckoning that turned 0.02 rad too much
        // each step (0.32 rad, more than half a metre off).
        let mut g = chain(&truth, |k| truth[k].in_frame_of(truth[k - 1]));
        let mut p = truth[0];
        for k in 1..truth.len() {
            let z = truth[k].in_frame_of(truth[k - 1]);
            p = p.compose(Pose2::new(z.x, z.y, z.theta + 0.02));
            g.nodes[k] = [f64::from(p.x), f64::from(p.y), f64::from(p.theta)];
        }
        g.add_edge(Edge {
            from: 0,
            to: 16,
            measured: Pose2::default(),
            information: step_info(),
        })
        .unwrap();
        assert!(worst(&g, &truth).0 > 0.5, "the start is not drifted");
        let done = g.optimise(20, 200);
        let (m, r) = worst(&g, &truth);
        assert!(
            m < 1e-3 && r < 1e-4,
            "{m} m, {r} rad off the truth ({done:?})"
        );
        assert!(
            done.error_after < 1e-6 * done.error_before.max(1.0),
            "{done:?}"
        );
    }

    #[test]
    fn a_closure_corrects_a_drifted_loop() {
        let truth = square();
        // The measured steps turn 0.02 rad too much: dead-reckoned, the loop ends far off.
        let mut g = chain(&truth, |k| {
            let z = truth[k].in_frame_of(truth[k - 1]);
            Pose2::new(z.x, z.y, z.theta + 0.02)
        });
        let before = worst(&g, &truth);
        let end_gap = g.pose(16).unwrap().position().distance(truth[0].position());
        assert!(end_gap > 0.5, "{end_gap}");
        g.add_edge(Edge {
            from: 0,
            to: 16,
            measured: Pose2::default(),
            information: [1e6, 1e6, 1e6],
        })
        .unwrap();
        g.optimise(20, 200);
        let after = worst(&g, &truth);
        let gap = g
            .pose(16)
            .unwrap()
            .position()
            .distance(g.pose(0).unwrap().position());
        assert!(gap < 0.01, "the loop stays open by {gap} m");
        // The residual drift is shared out along the loop: every node nearer the truth.
        assert!(
            after.0 < 0.25 * before.0 && after.1 < 0.25 * before.1,
            "{before:?} -> {after:?}"
        );
    }

    #[test]
    fn a_wrong_closure_of_little_information_barely_moves_the_graph() {
        let truth = square();
        let mut g = chain(&truth, |k| truth[k].in_frame_of(truth[k - 1]));
        // Claims the end is 1 m and 0.3 rad away from the start: wrong, but given as σ 3 m
        // and 3 rad against steps of σ 1 cm.
        g.add_edge(Edge {
            from: 0,
            to: 16,
            measured: Pose2::new(1.0, 0.0, 0.3),
            information: [0.1, 0.1, 0.1],
        })
        .unwrap();
        let done = g.optimise(20, 200);
        let (m, r) = worst(&g, &truth);
        assert!(m < 0.01 && r < 0.002, "{m} m, {r} rad ({done:?})");
        // The same closure given as σ 1 cm moves it: the test can tell.
        let mut h = chain(&truth, |k| truth[k].in_frame_of(truth[k - 1]));
        h.add_edge(Edge {
            from: 0,
            to: 16,
            measured: Pose2::new(1.0, 0.0, 0.3),
            information: [1e4, 1e4, 1e4],
        })
        .unwrap();
        h.optimise(20, 200);
        assert!(worst(&h, &truth).0 > 0.1);
    }

    #[test]
    fn full_stores_and_bad_edges_are_errors() {
        let mut g = PoseGraph::<2, 1>::new();
        g.add_node(Pose2::default()).unwrap();
        g.add_node(Pose2::new(1.0, 0.0, 0.0)).unwrap();
        assert_eq!(
            g.add_node(Pose2::default()),
            Err(GraphError::NodesFull { capacity: 2 })
        );
        let e = Edge {
            from: 0,
            to: 1,
            measured: Pose2::new(1.0, 0.0, 0.0),
            information: [1.0; 3],
        };
        assert_eq!(
            g.add_edge(Edge { to: 2, ..e }),
            Err(GraphError::BadEdge { from: 0, to: 2 })
        );
        assert_eq!(
            g.add_edge(Edge {
                information: [1.0, 0.0, 1.0],
                ..e
            }),
            Err(GraphError::NotFinite)
        );
        g.add_edge(e).unwrap();
        assert_eq!(g.add_edge(e), Err(GraphError::EdgesFull { capacity: 1 }));
        // The edge holds at its measurement; taken out, it leaves room for another.
        assert!(g.edge_error(0) < 1e-12 && g.edge_error(1) == 0.0);
        assert_eq!(g.pop_edge(), Some(e));
        assert_eq!(g.edge_count(), 0);
        assert_eq!(g.pop_edge(), None);
        assert_eq!(
            g.add_node(Pose2::new(f32::NAN, 0.0, 0.0)),
            Err(GraphError::NotFinite)
        );
    }
}
