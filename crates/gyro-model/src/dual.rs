//! Scalars the engine computes with: `f64`, and forward-mode dual numbers (`Jet`) that carry
//! exact first derivatives along a fixed number of directions.
//!
//! The engine is written once, generically over [`Real`]; evaluating it on `Jet<f64, N>` gives
//! the value together with N partial derivatives, and nesting (`Jet<Jet<f64, 1>, N>`) gives
//! directional derivatives of those (used for the exact Jacobian of the right-hand side).
//! Derivatives are propagated by the chain rule, never by differences: no cancellation.
//!
//! Why not `num-dual`: its vector duals wrap the derivative in an `Option` (a branch per
//! operation) and allocate for dynamic sizes; a fixed array per size, monomorphised for the few
//! chain sizes we use, is smaller. Measured like for like (the reference engine's Jacobian on
//! `Jet` and on num-dual 0.15's `Dual64` / `DualSVec64<8>`, the same generic code, Jacobians
//! equal to 3e-16) with `cargo bench --manifest-path crates/gyro-model/benches/num-dual/Cargo.toml`
//! (one run, quiet 2-core machine): with 8 directions a pass, as the model's Jacobian takes them,
//! num-dual costs 2.06× (Anschütz `full`), 2.36× (`gyroscopic`) and 1.35× (Foucault) of `Jet`;
//! with one direction a pass it costs 0.63–1.13×. Only the wide pass is on the hot path.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// The arithmetic the engine needs from a scalar.
pub trait Real:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + 'static
{
    /// A constant (all derivatives zero).
    fn cst(x: f64) -> Self;
    /// The real part.
    fn re(&self) -> f64;
    fn sin_cos(self) -> (Self, Self);
    fn sin(self) -> Self {
        self.sin_cos().0
    }
    fn cos(self) -> Self {
        self.sin_cos().1
    }
    fn sqrt(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn asin(self) -> Self;
    fn zero() -> Self {
        Self::cst(0.0)
    }
    fn one() -> Self {
        Self::cst(1.0)
    }
    /// Dense-solve hook for tape recording (`crate::tape`): the recording scalar records the
    /// solve of the leading n×n block of A x = b as one operation (LDLᵀ first if `spd_first`)
    /// and returns `Some`; every other scalar returns `None` and is eliminated as usual.
    fn record_solve<const N: usize>(
        _a: &[[Self; N]; N],
        _b: &mut [Self; N],
        _n: usize,
        _spd_first: bool,
    ) -> Option<bool> {
        None
    }
}

/// sin and cos as the engine computes them: `libm` (the Rust port of musl's, from FreeBSD's
/// msun) rather than the platform's. `f64::sin_cos` reaches glibc's `sincos` through a call
/// to the shared library; `libm::sincos` shares one range reduction and is compiled with the
/// workspace (still a call of its own where it is used: `perf` shows it and its `rem_pio2` at
/// 35 % and 4 % of the engine's Villarceau run at 5e-12). The functions alone (`cargo bench
/// -p gyro-model --bench trig`): 5.4 ns a pair against 8.8 ns over a 90° swing. A whole
/// Villarceau run, where the one pair is the right-hand side's only transcendental (`cargo
/// bench -p gyro-sim --bench handwritten`, old and new binaries alternated): 0.87× through the
/// engine, 0.89–0.91× hand-written, the same steps; whole scenes in docs/accuracy.md ("What
/// limits gyrolab"). Both are faithfully rounded (they differ from glibc's in the last bit for
/// ≈ 6 % of arguments). Everything that evaluates the equations —
/// the generic engine, the tapes, their native code and the hand-written references — uses
/// these, so that their results agree to the bit where they did. Inlining a copy of its
/// operations (the same bits on 14.6 M arguments in [−3, 3]) made the hand-written Villarceau
/// run at 5e-12 0.96× (1.378 → 1.327 ms, three alternations in one throwaway binary): the cost is
/// the polynomials' dependent chain, not the call, so the library is kept.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

impl Real for f64 {
    #[inline(always)]
    fn cst(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn re(&self) -> f64 {
        *self
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        sin_cos(self)
    }
    /// The first of [`sin_cos`], bit for bit (`libm` computes both from the same reduction).
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    /// The second of [`sin_cos`], bit for bit.
    #[inline(always)]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    #[inline(always)]
    fn asin(self) -> Self {
        f64::asin(self)
    }
}

/// A value with its first derivatives along N directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet<T: Real, const N: usize> {
    pub v: T,
    pub d: [T; N],
}

impl<T: Real, const N: usize> Jet<T, N> {
    #[inline(always)]
    pub fn constant(v: T) -> Self {
        Jet {
            v,
            d: [T::zero(); N],
        }
    }
    /// The variable number `i` (derivative 1 along direction i).
    #[inline(always)]
    pub fn variable(v: T, i: usize) -> Self {
        let mut d = [T::zero(); N];
        d[i] = T::one();
        Jet { v, d }
    }
    /// The first `n` of `q` as variables (coordinate i along direction i), zero beyond: the
    /// coordinates every chain walk differentiates along.
    #[inline(always)]
    pub fn variables(q: &[T], n: usize) -> [Self; N] {
        std::array::from_fn(|i| {
            if i < n {
                Jet::variable(q[i], i)
            } else {
                Jet::zero()
            }
        })
    }
    /// Chain rule for a scalar function with value `f` and derivative `df` at `self.v`.
    #[inline(always)]
    fn chain(self, f: T, df: T) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= df;
        }
        Jet { v: f, d }
    }
}

impl<T: Real, const N: usize> Add for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let mut d = self.d;
        for i in 0..N {
            d[i] += o.d[i];
        }
        Jet { v: self.v + o.v, d }
    }
}
impl<T: Real, const N: usize> Sub for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        let mut d = self.d;
        for i in 0..N {
            d[i] -= o.d[i];
        }
        Jet { v: self.v - o.v, d }
    }
}
impl<T: Real, const N: usize> Mul for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let mut d = [T::zero(); N];
        for i in 0..N {
            d[i] = self.d[i] * o.v + self.v * o.d[i];
        }
        Jet { v: self.v * o.v, d }
    }
}
impl<T: Real, const N: usize> Div for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let inv = T::one() / o.v;
        let v = self.v * inv;
        let mut d = [T::zero(); N];
        for i in 0..N {
            d[i] = (self.d[i] - v * o.d[i]) * inv;
        }
        Jet { v, d }
    }
}
impl<T: Real, const N: usize> Neg for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = -*x;
        }
        Jet { v: -self.v, d }
    }
}
impl<T: Real, const N: usize> AddAssign for Jet<T, N> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<T: Real, const N: usize> SubAssign for Jet<T, N> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<T: Real, const N: usize> MulAssign for Jet<T, N> {
    #[inline(always)]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl<T: Real, const N: usize> Add<f64> for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: f64) -> Self {
        Jet {
            v: self.v + o,
            d: self.d,
        }
    }
}
impl<T: Real, const N: usize> Sub<f64> for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: f64) -> Self {
        Jet {
            v: self.v - o,
            d: self.d,
        }
    }
}
impl<T: Real, const N: usize> Mul<f64> for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = *x * o;
        }
        Jet { v: self.v * o, d }
    }
}
impl<T: Real, const N: usize> Div<f64> for Jet<T, N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: f64) -> Self {
        self * (1.0 / o)
    }
}

impl<T: Real, const N: usize> Real for Jet<T, N> {
    #[inline(always)]
    fn cst(x: f64) -> Self {
        Jet::constant(T::cst(x))
    }
    #[inline(always)]
    fn re(&self) -> f64 {
        self.v.re()
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.v.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        self.chain(r, T::cst(0.5) / r)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx) / (x² + y²)
        let y = self;
        let r2 = x.v * x.v + y.v * y.v;
        let mut d = [T::zero(); N];
        for i in 0..N {
            d[i] = (x.v * y.d[i] - y.v * x.d[i]) / r2;
        }
        Jet {
            v: y.v.atan2(x.v),
            d,
        }
    }
    #[inline(always)]
    fn asin(self) -> Self {
        let one = T::one();
        self.chain(self.v.asin(), one / (one - self.v * self.v).sqrt())
    }
    /// Dual numbers over a recording scalar record a solve as solves of the values' matrix:
    /// x = A⁻¹b, then ẋₖ = A⁻¹(ḃₖ − Ȧₖ x) for each direction k that is not structurally zero.
    /// Over any other scalar: `None` (eliminate as usual).
    fn record_solve<const M: usize>(
        a: &[[Self; M]; M],
        b: &mut [Self; M],
        n: usize,
        spd_first: bool,
    ) -> Option<bool> {
        let av: [[T; M]; M] = a.map(|row| row.map(|x| x.v));
        let mut x: [T; M] = b.map(|x| x.v);
        let solved = T::record_solve(&av, &mut x, n, spd_first)?;
        let zero = T::zero();
        for k in 0..N {
            let mut rk = [zero; M];
            for i in 0..n {
                let mut s = b[i].d[k];
                for j in 0..n {
                    s -= a[i][j].d[k] * x[j];
                }
                rk[i] = s;
            }
            if rk[..n].iter().any(|r| *r != zero) {
                T::record_solve(&av, &mut rk, n, spd_first)?;
            }
            for i in 0..n {
                b[i].d[k] = rk[i];
            }
        }
        for i in 0..n {
            b[i].v = x[i];
        }
        Some(solved)
    }
}

/// A 3-vector of any scalar (kept minimal: the engine's hot loop uses only these operations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T>(pub [T; 3]);

impl<T: Real> V3<T> {
    #[inline(always)]
    pub fn zero() -> Self {
        V3([T::zero(); 3])
    }
    #[inline(always)]
    pub fn from_f64(a: [f64; 3]) -> Self {
        V3([T::cst(a[0]), T::cst(a[1]), T::cst(a[2])])
    }
    #[inline(always)]
    pub fn dot(&self, o: &Self) -> T {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    #[inline(always)]
    pub fn cross(&self, o: &Self) -> Self {
        let a = &self.0;
        let b = &o.0;
        V3([
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ])
    }
    #[inline(always)]
    pub fn add(&self, o: &Self) -> Self {
        V3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
    #[inline(always)]
    pub fn sub(&self, o: &Self) -> Self {
        V3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
    #[inline(always)]
    pub fn scale(&self, s: T) -> Self {
        V3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
    #[inline(always)]
    pub fn scale_f(&self, s: f64) -> Self {
        V3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
    pub fn re(&self) -> [f64; 3] {
        [self.0[0].re(), self.0[1].re(), self.0[2].re()]
    }
}

/// A 3×3 matrix of any scalar, row-major.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct M3<T>(pub [[T; 3]; 3]);

impl<T: Real> M3<T> {
    pub fn identity() -> Self {
        let o = T::zero();
        let l = T::one();
        M3([[l, o, o], [o, l, o], [o, o, l]])
    }
    pub fn from_f64(a: [[f64; 3]; 3]) -> Self {
        M3(a.map(|r| r.map(T::cst)))
    }
    #[inline(always)]
    pub fn mul_v(&self, v: &V3<T>) -> V3<T> {
        let m = &self.0;
        V3([
            m[0][0] * v.0[0] + m[0][1] * v.0[1] + m[0][2] * v.0[2],
            m[1][0] * v.0[0] + m[1][1] * v.0[1] + m[1][2] * v.0[2],
            m[2][0] * v.0[0] + m[2][1] * v.0[1] + m[2][2] * v.0[2],
        ])
    }
    /// Transpose times vector.
    #[inline(always)]
    pub fn tmul_v(&self, v: &V3<T>) -> V3<T> {
        let m = &self.0;
        V3([
            m[0][0] * v.0[0] + m[1][0] * v.0[1] + m[2][0] * v.0[2],
            m[0][1] * v.0[0] + m[1][1] * v.0[1] + m[2][1] * v.0[2],
            m[0][2] * v.0[0] + m[1][2] * v.0[1] + m[2][2] * v.0[2],
        ])
    }
    #[inline(always)]
    pub fn mul_m(&self, o: &Self) -> Self {
        let a = &self.0;
        let b = &o.0;
        let mut r = [[T::zero(); 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            }
        }
        M3(r)
    }
    /// Column j.
    #[inline(always)]
    pub fn col(&self, j: usize) -> V3<T> {
        V3([self.0[0][j], self.0[1][j], self.0[2][j]])
    }
    /// self · R_axis(angle) where R_axis is the elementary rotation about body axis 0/1/2:
    /// only two columns change, so this is 12 multiplications instead of 27.
    #[inline(always)]
    pub fn rotate_about_axis(&self, axis: usize, angle: T) -> Self {
        let (s, c) = angle.sin_cos();
        let (i, j) = match axis {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        let mut r = *self;
        for row in 0..3 {
            let a = self.0[row][i];
            let b = self.0[row][j];
            // new col i = c·a + s·b; new col j = −s·a + c·b
            r.0[row][i] = a * c + b * s;
            r.0[row][j] = b * c - a * s;
        }
        r
    }
    pub fn re(&self) -> [[f64; 3]; 3] {
        self.0.map(|r| r.map(|x| x.re()))
    }
}

/// Elementary rotation about axis 0/1/2 by `angle` (right-handed, counter-clockwise seen from the tip).
pub fn rot_axis<T: Real>(axis: usize, angle: T) -> M3<T> {
    M3::<T>::identity().rotate_about_axis(axis, angle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_and_cos_alone_are_the_pair_to_the_bit_and_faithful() {
        // The tape's interpreter evaluates Sin and Cos ops one at a time, its native code as a
        // pair, the generic engine as a pair: all three must give the same bits. And within an
        // ulp of the platform's (correctly rounded for nearly every argument).
        let mut x = -40.0f64;
        let mut differ = 0usize;
        let mut n = 0usize;
        while x < 40.0 {
            let (s, c) = sin_cos(x);
            assert_eq!(s.to_bits(), Real::sin(x).to_bits(), "sin at {x}");
            assert_eq!(c.to_bits(), Real::cos(x).to_bits(), "cos at {x}");
            for (a, b) in [(s, x.sin()), (c, x.cos())] {
                assert!(
                    (a - b).abs() <= f64::EPSILON * b.abs().max(f64::MIN_POSITIVE),
                    "{x}"
                );
                differ += usize::from(a != b);
            }
            n += 2;
            x += 3.3e-4;
        }
        for x in [0.0, -0.0, 1e-300, 1e-9, -1e-9, 1e6, 1e22] {
            assert_eq!(sin_cos(x).0.to_bits(), Real::sin(x).to_bits(), "sin at {x}");
            assert_eq!(sin_cos(x).1.to_bits(), Real::cos(x).to_bits(), "cos at {x}");
        }
        // A cheaper pair that was just wrong would differ far more often than an ulp's flip.
        assert!(differ * 5 < n, "{differ} of {n} differ from the platform's");
    }

    #[test]
    fn jet_derivatives_match_calculus() {
        // f(x, y) = sin(x)·y / (1 + x²) + atan2(y, x)
        let x = Jet::<f64, 2>::variable(0.7, 0);
        let y = Jet::<f64, 2>::variable(-1.3, 1);
        let f = x.sin() * y / (x * x + 1.0) + y.atan2(x);
        let (xv, yv) = (0.7f64, -1.3f64);
        let dfdx = (xv.cos() * yv * (1.0 + xv * xv) - xv.sin() * yv * 2.0 * xv)
            / (1.0 + xv * xv).powi(2)
            - yv / (xv * xv + yv * yv);
        let dfdy = xv.sin() / (1.0 + xv * xv) + xv / (xv * xv + yv * yv);
        assert!((f.d[0] - dfdx).abs() < 1e-14);
        assert!((f.d[1] - dfdy).abs() < 1e-14);
    }

    #[test]
    fn nested_jets_give_second_derivatives() {
        // d²/dt² sin(t²) at t = 0.9
        let t = Jet::<Jet<f64, 1>, 1> {
            v: Jet::variable(0.9, 0),
            d: [Jet::constant(1.0)],
        };
        let f = (t * t).sin();
        let tv = 0.9f64;
        let second = 2.0 * (tv * tv).cos() - 4.0 * tv * tv * (tv * tv).sin();
        assert!((f.d[0].d[0] - second).abs() < 1e-13);
    }

    #[test]
    fn elementary_rotation_follows_beghin_convention() {
        // R_y(θ) takes the North axis to (cos θ, 0, −sin θ): positive tilt = North end down.
        let r = rot_axis(1, 0.3f64);
        let x = r.col(0);
        assert!((x.0[0] - 0.3f64.cos()).abs() < 1e-15 && (x.0[2] + 0.3f64.sin()).abs() < 1e-15);
        // R_z(ζ) takes North towards West for ζ > 0.
        let z = rot_axis(2, 0.2f64).col(0);
        assert!(z.0[1] > 0.0);
    }
}
