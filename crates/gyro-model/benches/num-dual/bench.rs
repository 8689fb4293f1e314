//! gyro-model's dual numbers (`Jet`) against num-dual's (`Dual64`, `DualSVec64<D>`) on the
//! engine's right-hand side, like for like: the engine is generic over [`Real`], so the same
//! code (`CompiledModel::rhs_reference`, the world-axes reference engine, whose Lagrangian
//! derivative is itself taken on `Jet<T, N>` of the scalar `T`) is run with each library's dual
//! as `T`, and gives the exact Jacobian of ẋ = f(x): column by column on one-direction duals
//! (`Jet<f64, 1>` / `Dual64`), and 8 columns a pass on vector duals (`Jet<f64, 8>` /
//! `DualSVec64<8>`, as `CompiledModel::jacobian` does). Each pair is checked to give the same
//! Jacobian. num-dual's types enter through a newtype (`Real` is gyro-model's trait and the duals
//! are num-dual's types) whose operations forward to num-dual's and are inlined.
//!
//! `cargo bench --manifest-path crates/gyro-model/benches/num-dual/Cargo.toml`
//! (prints one line per design and fidelity: µs per Jacobian with each, and the ratio).

use std::fmt::Debug;
use std::hint::black_box;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};
use std::time::Instant;

use gyro_model::{
    BaseEffects, CompiledModel, Design, Effects, Fidelity, InitialCondition, Jet, ModelOptions,
    Moored, Real,
};
use num_dual::{Dual64, DualNum, DualSVec64, DualStruct};

/// Width of the vector duals: the columns one pass of the Jacobian carries.
const D: usize = 8;

/// A num-dual number as a gyro-model scalar. Equality is on the value and the derivatives (the
/// engine skips work where a derivative is zero; num-dual's own `==` compares values only).
#[derive(Clone, Copy, Debug)]
struct Nd<X>(X);

impl PartialEq for Nd<Dual64> {
    #[inline(always)]
    fn eq(&self, o: &Self) -> bool {
        self.0.re == o.0.re && self.0.eps == o.0.eps
    }
}
impl PartialEq for Nd<DualSVec64<D>> {
    #[inline(always)]
    fn eq(&self, o: &Self) -> bool {
        self.0.re == o.0.re && self.0.eps == o.0.eps
    }
}

macro_rules! forward_ops {
    ($($tr:ident $f:ident, $atr:ident $af:ident;)*) => {$(
        impl<X: DualNum<Primitive = f64> + Copy> $tr for Nd<X> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Nd(<X as $tr<X>>::$f(self.0, o.0))
            }
        }
        impl<X: DualNum<Primitive = f64> + Copy> $tr<f64> for Nd<X> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: f64) -> Self {
                Nd(<X as $tr<f64>>::$f(self.0, o))
            }
        }
        impl<X: DualNum<Primitive = f64> + Copy> $atr for Nd<X> {
            #[inline(always)]
            fn $af(&mut self, o: Self) {
                <X as $atr<X>>::$af(&mut self.0, o.0)
            }
        }
    )*};
}
forward_ops! {
    Add add, AddAssign add_assign;
    Sub sub, SubAssign sub_assign;
    Mul mul, MulAssign mul_assign;
}
impl<X: DualNum<Primitive = f64> + Copy> Div for Nd<X> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Nd(self.0 / o.0)
    }
}
impl<X: DualNum<Primitive = f64> + Copy> Div<f64> for Nd<X> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: f64) -> Self {
        Nd(self.0 / o)
    }
}
impl<X: DualNum<Primitive = f64> + Copy> Neg for Nd<X> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Nd(-self.0)
    }
}

impl<X> Real for Nd<X>
where
    X: DualNum<Primitive = f64> + DualStruct<Real = f64> + Copy + Debug,
    Nd<X>: PartialEq,
{
    #[inline(always)]
    fn cst(x: f64) -> Self {
        Nd(X::from(x))
    }
    #[inline(always)]
    fn re(&self) -> f64 {
        DualStruct::re(&self.0)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.0.sin_cos();
        (Nd(s), Nd(c))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Nd(self.0.sqrt())
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        Nd(self.0.atan2(x.0))
    }
    #[inline(always)]
    fn asin(self) -> Self {
        Nd(self.0.asin())
    }
}

/// How a dual type seeds direction `k` of `D` and reads it back.
trait Seed: Real {
    const WIDTH: usize;
    fn seeded(v: f64, k: Option<usize>) -> Self;
    fn part(&self, k: usize) -> f64;
}
impl Seed for Jet<f64, 1> {
    const WIDTH: usize = 1;
    fn seeded(v: f64, k: Option<usize>) -> Self {
        Jet {
            v,
            d: [if k.is_some() { 1.0 } else { 0.0 }],
        }
    }
    fn part(&self, _: usize) -> f64 {
        self.d[0]
    }
}
impl Seed for Nd<Dual64> {
    const WIDTH: usize = 1;
    fn seeded(v: f64, k: Option<usize>) -> Self {
        match k {
            Some(_) => Nd(Dual64::from_re(v).derivative()),
            None => Nd(Dual64::from_re(v)),
        }
    }
    fn part(&self, _: usize) -> f64 {
        self.0.eps
    }
}
impl Seed for Jet<f64, D> {
    const WIDTH: usize = D;
    fn seeded(v: f64, k: Option<usize>) -> Self {
        match k {
            Some(k) => Jet::variable(v, k),
            None => Jet::constant(v),
        }
    }
    fn part(&self, k: usize) -> f64 {
        self.d[k]
    }
}
impl Seed for Nd<DualSVec64<D>> {
    const WIDTH: usize = D;
    fn seeded(v: f64, k: Option<usize>) -> Self {
        match k {
            Some(k) => Nd(DualSVec64::<D>::from_re(v).derivative(k)),
            None => Nd(DualSVec64::<D>::from_re(v)),
        }
    }
    fn part(&self, k: usize) -> f64 {
        self.0.eps.0.as_ref().map_or(0.0, |e| e[k])
    }
}

/// The Jacobian of `m.rhs_reference` at `x`, `S::WIDTH` columns a pass.
fn jacobian<S: Seed>(
    m: &CompiledModel<Moored>,
    fidelity: Fidelity,
    x: &[f64],
    xs: &mut [S],
    dxs: &mut [S],
    jac: &mut [f64],
) {
    let dim = x.len();
    let mut first = 0;
    while first < dim {
        for i in 0..dim {
            let k = (i >= first && i - first < S::WIDTH).then(|| i - first);
            xs[i] = S::seeded(x[i], k);
        }
        m.rhs_reference(fidelity, S::cst(1.0), xs, dxs);
        for row in 0..dim {
            for col in first..dim.min(first + S::WIDTH) {
                jac[row * dim + col] = dxs[row].part(col - first);
            }
        }
        first += S::WIDTH;
    }
}

/// Seconds per call of `f`: the best of 7 batches of about 0.2 s each.
fn time_per_call(mut f: impl FnMut()) -> f64 {
    let started = Instant::now();
    let mut calls = 0u64;
    while started.elapsed().as_secs_f64() < 0.05 {
        f();
        calls += 1;
    }
    let per_batch = ((0.2 / 0.05) * calls as f64).max(1.0) as u64;
    (0..7)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..per_batch {
                f();
            }
            t.elapsed().as_secs_f64() / per_batch as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn model(name: &str, fidelity: Fidelity) -> Option<CompiledModel<Moored>> {
    // Cargo's value when it runs the bench, not the compiled one (.ci/test_paths.py says why).
    let dir = std::env::var("CARGO_MANIFEST_DIR").ok()?;
    let path = format!("{dir}/../../../../designs/{name}.toml");
    let text = std::fs::read_to_string(path).ok()?;
    let d = Design::from_toml(&format!("{name}.toml"), &text, &[]).ok()?;
    let mut effects = Effects::all();
    effects.base = BaseEffects {
        earth_rotation: true,
        ..Default::default()
    };
    let m = CompiledModel::compile(
        d,
        Moored {
            latitude_rad: 50f64.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity,
            effects,
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: true,
                offsets_rad: vec![(0, 0.1)],
                ..Default::default()
            },
        },
    )
    .ok()?;
    (m.fidelity == fidelity).then_some(m)
}

/// Largest |a − b| relative to the largest |a|.
fn differs(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

fn pair<A: Seed, B: Seed>(m: &CompiledModel<Moored>, fidelity: Fidelity, label: &str) -> f64 {
    let x = m.x0.clone();
    let dim = x.len();
    let (mut xa, mut dxa) = (vec![A::zero(); dim], vec![A::zero(); dim]);
    let (mut xb, mut dxb) = (vec![B::zero(); dim], vec![B::zero(); dim]);
    let (mut ja, mut jb) = (vec![0.0; dim * dim], vec![0.0; dim * dim]);
    jacobian(m, fidelity, &x, &mut xa, &mut dxa, &mut ja);
    jacobian(m, fidelity, &x, &mut xb, &mut dxb, &mut jb);
    let diff = differs(&ja, &jb);
    assert!(diff < 1e-12, "{label}: the Jacobians differ by {diff:e}");
    let ta = time_per_call(|| {
        jacobian(m, fidelity, black_box(&x), &mut xa, &mut dxa, &mut ja);
        black_box(&ja);
    });
    let tb = time_per_call(|| {
        jacobian(m, fidelity, black_box(&x), &mut xb, &mut dxb, &mut jb);
        black_box(&jb);
    });
    println!(
        "  {label:<34} Jet {:>9.2} µs   num-dual {:>9.2} µs   num-dual / Jet {:>5.2}   (Jacobians agree to {diff:.0e})",
        ta * 1e6,
        tb * 1e6,
        tb / ta
    );
    tb / ta
}

fn main() {
    let mut ratios = Vec::new();
    for name in ["anschutz-1906", "foucault-gyroscope"] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic] {
            let Some(m) = model(name, fidelity) else {
                continue;
            };
            let x = m.x0.clone();
            let mut dx = vec![0.0; x.len()];
            let t_f64 = time_per_call(|| {
                black_box(m.rhs_reference(fidelity, 1.0, black_box(&x), &mut dx));
            });
            println!(
                "{name} / {fidelity}: {} states, ẋ on f64 {:.2} µs",
                x.len(),
                t_f64 * 1e6
            );
            ratios.push(pair::<Jet<f64, 1>, Nd<Dual64>>(
                &m,
                fidelity,
                "Jacobian, 1 column a pass",
            ));
            ratios.push(pair::<Jet<f64, D>, Nd<DualSVec64<D>>>(
                &m,
                fidelity,
                "Jacobian, 8 columns a pass",
            ));
        }
    }
    let geo = (ratios.iter().map(|r| r.ln()).sum::<f64>() / ratios.len() as f64).exp();
    println!(
        "num-dual / Jet: geometric mean {geo:.2}, range {:.2} … {:.2}",
        ratios.iter().copied().fold(f64::INFINITY, f64::min),
        ratios.iter().copied().fold(0.0, f64::max)
    );
}
