//! The general iterative learning observer (paper eq. 9, Chen & Chowdhury 2007) for small
//! const-generic dimensions, and the check of Theorem 3.1's condition.
//!
//! System: `dx/dt = A x + B u + F theta(t)`, `y = C x`, with `N` states, `U` inputs, `P`
//! outputs, `M` unknown parameters `theta`. Observer with learning delay `tau = D h`:
//!
//! ```text
//! dxhat/dt = A xhat + B u + L (y - C xhat) + F v(t)
//! v(t)     = K1 v(t - tau) + K2 (y - C xhat)
//! ```
//!
//! Theorem 3.1: if `(A - LC)^T P + P (A - LC) = -Q` with `Q > 0`, `P > 0`,
//! `P F = (K2 C)^T` and `0 < K1^T K1 <= I`, state and parameter errors stay bounded.
//! [`check_theorem_3_1`] solves the Lyapunov equation for given `L`, `Q` and checks the rest.
//!
//! The second-order ILO for acceleration (`A = [[0,1],[0,0]]`, `C = [1 0]`, `F = [0 1]^T`)
//! cannot satisfy it: `C F = 0` gives `F^T P F = F^T (K2 C)^T = (K2 C F)^T = 0`, impossible for
//! `P > 0` (see the tests). Hence the paper's series connection.

// The config-time linear algebra below indexes fixed-size matrices with loop bounds equal to
// their const dimensions; index loops read like the formulas and cannot go out of bounds.
#![allow(clippy::needless_range_loop)]

use crate::error::positive;
use crate::{ConfigError, Real};

/// Row-major `R x C` matrix of `T`.
pub type Mat<T, const R: usize, const C: usize> = [[T; C]; R];

/// Matrices of the general ILO, in `f64` (converted to `T` at construction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeneralIloConfig<const N: usize, const U: usize, const P: usize, const M: usize> {
    /// System matrix `A` (N x N), 1/s.
    pub a: Mat<f64, N, N>,
    /// Input matrix `B` (N x U).
    pub b: Mat<f64, N, U>,
    /// Output matrix `C` (P x N).
    pub c: Mat<f64, P, N>,
    /// Parameter input matrix `F` (N x M).
    pub f: Mat<f64, N, M>,
    /// Observer gain `L` (N x P), 1/s.
    pub l: Mat<f64, N, P>,
    /// Learning gain `K1` (M x M), dimensionless.
    pub k1: Mat<f64, M, M>,
    /// Learning gain `K2` (M x P).
    pub k2: Mat<f64, M, P>,
}

/// The general ILO state: `xhat` and the delay line of `v` (`[[T; M]; D]`).
///
/// RAM: `N + M (D + 1)` state words plus the coefficient matrices
/// (`N^2 + N U + P N + N M + N P + M^2 + M P` words) of `T`.
#[derive(Clone, Copy, Debug)]
pub struct GeneralIlo<
    T: Real,
    const N: usize,
    const U: usize,
    const P: usize,
    const M: usize,
    const D: usize,
> {
    ha: Mat<T, N, N>,
    hb: Mat<T, N, U>,
    c: Mat<T, P, N>,
    hf: Mat<T, N, M>,
    hl: Mat<T, N, P>,
    k1: Mat<T, M, M>,
    k2: Mat<T, M, P>,
    xhat: [T; N],
    v: [T; M],
    buf: [[T; M]; D],
    head: u32,
}

fn conv<T: Real, const R: usize, const C: usize>(m: &Mat<f64, R, C>, s: f64) -> Mat<T, R, C> {
    m.map(|row| row.map(|x| T::from_f64(x * s)))
}

fn all_finite<const R: usize, const C: usize>(m: &Mat<f64, R, C>) -> bool {
    m.iter().flatten().all(|x| x.is_finite())
}

impl<T: Real, const N: usize, const U: usize, const P: usize, const M: usize, const D: usize>
    GeneralIlo<T, N, U, P, M, D>
{
    const SHAPE_OK: () = assert!(
        N >= 1 && P >= 1 && M >= 1 && D >= 1 && D <= u32::MAX as usize,
        "empty ILO shape"
    );

    /// Builds the observer for step `h` (s). Errors: non-finite matrix entries, `h <= 0`.
    /// (Whether the gains are stabilising is [`check_theorem_3_1`]'s business.)
    pub fn new(cfg: &GeneralIloConfig<N, U, P, M>, h: f32) -> Result<Self, ConfigError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        let h = positive("h", f64::from(h))?;
        if !(all_finite(&cfg.a)
            && all_finite(&cfg.b)
            && all_finite(&cfg.c)
            && all_finite(&cfg.f)
            && all_finite(&cfg.l)
            && all_finite(&cfg.k1)
            && all_finite(&cfg.k2))
        {
            return Err(ConfigError::NotFinite("matrix"));
        }
        Ok(Self {
            ha: conv(&cfg.a, h),
            hb: conv(&cfg.b, h),
            c: conv(&cfg.c, 1.0),
            hf: conv(&cfg.f, h),
            hl: conv(&cfg.l, h),
            k1: conv(&cfg.k1, 1.0),
            k2: conv(&cfg.k2, 1.0),
            xhat: [T::ZERO; N],
            v: [T::ZERO; M],
            buf: [[T::ZERO; M]; D],
            head: 0,
        })
    }

    /// Sets `xhat = x0` and every `v` to 0.
    pub fn reset(&mut self, x0: [T; N]) {
        self.xhat = x0;
        self.v = [T::ZERO; M];
        self.buf = [[T::ZERO; M]; D];
        self.head = 0;
    }

    /// One explicit Euler step with known input `u` and measurement `y`, `e_n = y_n - C xhat_n`:
    ///
    /// ```text
    /// v_n        = K1 v_{n-D} + K2 e_n
    /// xhat_{n+1} = xhat_n + h (A xhat_n + B u_n + L e_n + F v_n)
    /// ```
    /// Returns `v_n` (the estimate of `theta`).
    pub fn step(&mut self, u: &[T; U], y: &[T; P]) -> [T; M] {
        let mut e = *y;
        for (ei, crow) in e.iter_mut().zip(self.c.iter()) {
            *ei = *ei - dot(crow, &self.xhat);
        }
        let hd = self.head as usize;
        let old = self.buf.get(hd).copied().unwrap_or([T::ZERO; M]);
        let mut v = [T::ZERO; M];
        for ((vi, k1row), k2row) in v.iter_mut().zip(self.k1.iter()).zip(self.k2.iter()) {
            *vi = dot(k1row, &old) + dot(k2row, &e);
        }
        if let Some(slot) = self.buf.get_mut(hd) {
            *slot = v;
        }
        self.head = if hd + 1 >= D { 0 } else { self.head + 1 };
        let mut next = self.xhat;
        for (i, x) in next.iter_mut().enumerate() {
            let mut d = T::ZERO;
            if let (Some(ra), Some(rb), Some(rl), Some(rf)) = (
                self.ha.get(i),
                self.hb.get(i),
                self.hl.get(i),
                self.hf.get(i),
            ) {
                d = dot(ra, &self.xhat) + dot(rb, u) + dot(rl, &e) + dot(rf, &v);
            }
            *x = *x + d;
        }
        self.xhat = next;
        self.v = v;
        v
    }

    /// State estimate `xhat`.
    pub fn xhat(&self) -> [T; N] {
        self.xhat
    }

    /// Parameter estimate `v` of the last step.
    pub fn theta(&self) -> [T; M] {
        self.v
    }
}

fn dot<T: Real, const K: usize>(a: &[T; K], b: &[T; K]) -> T {
    a.iter()
        .zip(b.iter())
        .fold(T::ZERO, |acc, (x, y)| acc + *x * *y)
}

/// The result of [`check_theorem_3_1`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Theorem31<const N: usize> {
    /// The solution `P` of `(A - LC)^T P + P (A - LC) = -Q` (if the equation is solvable).
    pub p: Option<Mat<f64, N, N>>,
    /// `Q` is symmetric positive definite.
    pub q_positive: bool,
    /// `P` is symmetric positive definite.
    pub p_positive: bool,
    /// `max |P F - (K2 C)^T|` (infinity if `P` does not exist).
    pub spr_residual: f64,
    /// `0 < K1^T K1 <= I` (every eigenvalue of `K1^T K1` in `(0, 1]`, within 1e-12).
    pub k1_ok: bool,
}

impl<const N: usize> Theorem31<N> {
    /// All conditions hold (`P F = (K2 C)^T` within `tol`).
    pub fn satisfied(&self, tol: f64) -> bool {
        self.q_positive && self.p_positive && self.spr_residual <= tol && self.k1_ok
    }
}

/// Largest state dimension [`check_theorem_3_1`] solves (the Lyapunov system is `N^2 x N^2`).
pub const LYAP_MAX: usize = 4;

/// Solves `Ac^T P + P Ac = -Q` by Gaussian elimination on the `N^2` vectorised unknowns
/// (`N <= LYAP_MAX`). `None` if singular (e.g. `Ac` has eigenvalues `a + b = 0`) or too large.
pub fn lyapunov<const N: usize>(ac: &Mat<f64, N, N>, q: &Mat<f64, N, N>) -> Option<Mat<f64, N, N>> {
    const MX: usize = LYAP_MAX * LYAP_MAX;
    if N > LYAP_MAX {
        return None;
    }
    let nn = N * N;
    let mut sys = [[0.0f64; MX + 1]; MX];
    // unknown index of P[i][j] = i * N + j; equation (i, j):
    // sum_k Ac[k][i] P[k][j] + sum_k P[i][k] Ac[k][j] = -Q[i][j]
    for i in 0..N {
        for j in 0..N {
            let row = &mut sys[i * N + j];
            for k in 0..N {
                row[k * N + j] += ac[k][i];
                row[i * N + k] += ac[k][j];
            }
            row[MX] = -q[i][j];
        }
    }
    for col in 0..nn {
        let piv = (col..nn).max_by(|&a, &b| {
            libm::fabs(sys[a][col])
                .partial_cmp(&libm::fabs(sys[b][col]))
                .unwrap_or(core::cmp::Ordering::Equal)
        })?;
        if libm::fabs(sys[piv][col]) < 1e-14 {
            return None;
        }
        sys.swap(col, piv);
        let pr = sys[col];
        for (r, row) in sys.iter_mut().enumerate().take(nn) {
            if r != col {
                let fac = row[col] / pr[col];
                for c in col..=MX {
                    row[c] -= fac * pr[c];
                }
            }
        }
    }
    let mut p = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..N {
            p[i][j] = sys[i * N + j][MX] / sys[i * N + j][i * N + j];
        }
    }
    Some(p)
}

/// Symmetric positive definite (Cholesky succeeds and the matrix is symmetric within 1e-9).
pub fn positive_definite<const N: usize>(a: &Mat<f64, N, N>) -> bool {
    let mut l = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..N {
            if libm::fabs(a[i][j] - a[j][i]) > 1e-9 * (1.0 + libm::fabs(a[i][j])) {
                return false;
            }
        }
    }
    for i in 0..N {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s <= 0.0 {
                    return false;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    true
}

/// Checks Theorem 3.1's condition for the observer gains `L`, `K1`, `K2` of `cfg` and a
/// Lyapunov weight `Q` (host or test use; `f64`).
pub fn check_theorem_3_1<const N: usize, const U: usize, const P: usize, const M: usize>(
    cfg: &GeneralIloConfig<N, U, P, M>,
    q: &Mat<f64, N, N>,
) -> Theorem31<N> {
    // Ac = A - L C
    let mut ac = cfg.a;
    for i in 0..N {
        for j in 0..N {
            for k in 0..P {
                ac[i][j] -= cfg.l[i][k] * cfg.c[k][j];
            }
        }
    }
    let p = lyapunov(&ac, q);
    let q_positive = positive_definite(q);
    let (p_positive, spr_residual) = match &p {
        None => (false, f64::INFINITY),
        Some(pm) => {
            let mut r: f64 = 0.0;
            for i in 0..N {
                for j in 0..M {
                    let mut pf = 0.0;
                    for k in 0..N {
                        pf += pm[i][k] * cfg.f[k][j];
                    }
                    // (K2 C)^T [i][j] = (K2 C)[j][i] = sum_k K2[j][k] C[k][i]
                    let mut k2c = 0.0;
                    for k in 0..P {
                        k2c += cfg.k2[j][k] * cfg.c[k][i];
                    }
                    r = r.max(libm::fabs(pf - k2c));
                }
            }
            (positive_definite(pm), r)
        }
    };
    // 0 < K1^T K1 <= I  <=>  K1^T K1 > 0 and I - K1^T K1 >= 0
    let mut g = [[0.0f64; M]; M];
    for i in 0..M {
        for j in 0..M {
            for k in 0..M {
                g[i][j] += cfg.k1[k][i] * cfg.k1[k][j];
            }
        }
    }
    let mut ig = g.map(|row| row.map(|x| -x));
    for (i, row) in ig.iter_mut().enumerate() {
        row[i] += 1.0 + 1e-12;
    }
    let k1_ok = positive_definite(&g) && positive_definite(&ig);
    Theorem31 {
        p,
        q_positive,
        p_positive,
        spr_residual,
        k1_ok,
    }
}
