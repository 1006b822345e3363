//! The contact measurement model as a least-squares problem ([`SocketProblem`]: the
//! contacts, the sockets' unknown positions, the weights; module docs, measurement model), its
//! noise settings ([`SIGMA_CHANGE`], [`MIN_SIGMA`]) and a finite-difference Jacobian to check
//! it ([`numeric_jacobian`]). Residuals in metres.

use super::*;

/// The contact noise estimate is iterated until it changes by less than this fraction.
pub const SIGMA_CHANGE: f64 = 0.05;

/// Passes of the noise re-estimation per step (fit, re-weight, refit).
pub(super) const SIGMA_PASSES: usize = 4;

/// Smallest contact noise used to weight a distance (metres, 0.1 µm): far below any hand-placed
/// ball, it only keeps the weight finite on noise-free data.
pub const MIN_SIGMA: f64 = 1e-7;

/// A contact sample: joint values in row order, the target and the socket index.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// One value per model row (radians or metres).
    pub q: Vec<f64>,
    /// Target index.
    pub target: usize,
    /// Socket index.
    pub socket: usize,
}

/// A known distance between two sockets.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketConstraint {
    /// First socket index.
    pub a: usize,
    /// Second socket index.
    pub b: usize,
    /// Centre-to-centre distance (metres).
    pub distance: f64,
    /// Its standard deviation (metres).
    pub sigma: f64,
}

/// The contact problem (see the module docs): the model's parameters, then three per socket.
#[derive(Clone, Copy, Debug)]
pub struct SocketProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// Contact samples.
    pub contacts: &'a [Contact],
    /// Known distances.
    pub constraints: &'a [SocketConstraint],
    /// Number of sockets.
    pub sockets: usize,
    /// The contact noise `σ_point` that weights the distances (metres).
    pub sigma_point: f64,
}

impl SocketProblem<'_> {
    /// Index of the first socket parameter (`socket 0 .x`).
    pub fn socket_offset(&self) -> usize {
        self.model.parameter_count()
    }

    /// Socket `s`'s centre at `x` (metres, device frame).
    pub fn socket_at(&self, x: &[f64], s: usize) -> Vector3<f64> {
        let o = self.socket_offset() + 3 * s;
        Vector3::new(
            x.get(o).copied().unwrap_or(0.0),
            x.get(o + 1).copied().unwrap_or(0.0),
            x.get(o + 2).copied().unwrap_or(0.0),
        )
    }

    pub(super) fn observed(&self, x: &[f64], c: &Contact) -> Observed {
        Observed::new(
            c.q.clone(),
            Observation::Point {
                target: c.target,
                point: self.socket_at(x, c.socket),
            },
        )
    }

    pub(super) fn weight(&self, k: &SocketConstraint) -> f64 {
        self.sigma_point / k.sigma
    }
}

impl Problem for SocketProblem<'_> {
    fn parameter_count(&self) -> usize {
        self.model.parameter_count() + 3 * self.sockets
    }
    fn block_count(&self) -> usize {
        self.contacts.len() + self.constraints.len()
    }
    fn block_size(&self, block: usize) -> usize {
        if block < self.contacts.len() {
            3
        } else {
            1
        }
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        if let Some(c) = self.contacts.get(block) {
            self.model.residuals(x, &self.observed(x, c), out);
        } else if let Some(k) = self.constraints.get(block - self.contacts.len()) {
            let d = self.socket_at(x, k.a) - self.socket_at(x, k.b);
            out[0] = (d.norm() - k.distance) * self.weight(k);
        }
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        let offset = self.socket_offset();
        let nc = columns.len();
        jacobian[..self.block_size(block) * nc].fill(0.0);
        // Socket columns: which socket and axis, or None for a model column.
        let socket_of = |c: usize| (c >= offset).then(|| ((c - offset) / 3, (c - offset) % 3));
        if let Some(c) = self.contacts.get(block) {
            let model_cols: Vec<usize> = columns.iter().copied().filter(|&c| c < offset).collect();
            let mut jm = vec![0.0; 3 * model_cols.len()];
            self.model
                .jacobian(x, &self.observed(x, c), &model_cols, residuals, &mut jm);
            let mut m = 0;
            for (k, &col) in columns.iter().enumerate() {
                match socket_of(col) {
                    None => {
                        for i in 0..3 {
                            jacobian[i * nc + k] = jm[i * model_cols.len() + m];
                        }
                        m += 1;
                    }
                    // r = p − s: ∂r/∂s = −I.
                    Some((s, axis)) if s == c.socket => jacobian[axis * nc + k] = -1.0,
                    Some(_) => {}
                }
            }
        } else if let Some(k) = self.constraints.get(block - self.contacts.len()) {
            let d = self.socket_at(x, k.a) - self.socket_at(x, k.b);
            let n = d.norm();
            let w = self.weight(k);
            residuals[0] = (n - k.distance) * w;
            // ∂‖d‖/∂s_a = d/‖d‖ = −∂‖d‖/∂s_b (zero at coincident sockets, a saddle).
            let u = if n > 0.0 { d / n } else { Vector3::zeros() };
            for (col, &c) in columns.iter().enumerate() {
                match socket_of(c) {
                    Some((s, axis)) if s == k.a => jacobian[col] += w * u[axis],
                    Some((s, axis)) if s == k.b => jacobian[col] -= w * u[axis],
                    _ => {}
                }
            }
        }
    }
}

/// The Jacobian of the problem at `x` by central differences (step `h` in parameter units),
/// row-major over all blocks; for tests of the analytic one.
pub fn numeric_jacobian(problem: &SocketProblem<'_>, x: &[f64], h: f64) -> DMatrix<f64> {
    let n = problem.parameter_count();
    let rows: usize = (0..problem.block_count())
        .map(|b| problem.block_size(b))
        .sum();
    let mut j = DMatrix::zeros(rows, n);
    let mut xp = x.to_vec();
    let mut rp = [0.0; 3];
    let mut rm = [0.0; 3];
    for c in 0..n {
        let mut row = 0;
        for b in 0..problem.block_count() {
            let m = problem.block_size(b);
            xp[c] = x[c] + h;
            problem.residuals(&xp, b, &mut rp[..m]);
            xp[c] = x[c] - h;
            problem.residuals(&xp, b, &mut rm[..m]);
            xp[c] = x[c];
            for i in 0..m {
                j[(row + i, c)] = (rp[i] - rm[i]) / (2.0 * h);
            }
            row += m;
        }
    }
    j
}
