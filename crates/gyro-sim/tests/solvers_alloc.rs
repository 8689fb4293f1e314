//! No allocation inside the step loop: the number of heap allocations made by `integrate`
//! does not grow with the number of steps, for every method. Counted by a global allocator
//! wrapper (per thread, so parallel tests do not interfere).

// A counting GlobalAlloc needs `unsafe impl`; it only forwards to the system allocator.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ops::ControlFlow;

use gyro_sim::solvers::{Method, OdeSystem, OutputGrid, Tolerances, integrate};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

struct Pendulum;
impl OdeSystem for Pendulum {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], d: &mut [f64]) {
        d[0] = x[1];
        d[1] = -x[0].sin();
    }
}

fn allocations_for(method: Method, t_end: f64) -> (u64, u64) {
    let tol = Tolerances {
        rtol: 1e-9,
        atol: 1e-12,
        max_step_s: f64::INFINITY,
        initial_step_s: None,
        jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
    };
    let grid = OutputGrid {
        t0: 0.0,
        dt: 0.05,
        t_end,
    };
    let mut x = [1.0, 0.0];
    let before = ALLOCATIONS.with(Cell::get);
    let result = integrate(
        &mut Pendulum,
        method,
        &tol,
        &mut x,
        &grid,
        &[3.0, 7.0],
        |_, _| ControlFlow::Continue(()),
    );
    let after = ALLOCATIONS.with(Cell::get);
    let steps = result.map(|(_, s)| s.steps).unwrap_or(0);
    (after - before, steps)
}

#[test]
fn allocations_do_not_grow_with_steps() {
    for method in [
        Method::Dopri5,
        Method::Dop853,
        Method::Vern9,
        Method::Rk4 { step_s: 1e-2 },
        Method::Rodas4,
        Method::Rodas5p,
        Method::Radau5,
    ] {
        let (short, short_steps) = allocations_for(method, 10.0);
        let (long, long_steps) = allocations_for(method, 200.0);
        assert!(long_steps > 10 * short_steps, "{method}");
        assert_eq!(
            short, long,
            "{method}: allocations grow with the run length"
        );
        assert!(short < 40, "{method}: {short} allocations");
    }
}

/// The compiled model's right-hand side and Jacobian (its recorded tapes) allocate nothing once
/// warm: the tapes are recorded and the evaluation buffer sized by the first calls.
#[test]
fn model_evaluation_does_not_allocate_once_warm() {
    use gyro_sim::{Scene, SceneOverrides, Simulation};
    for (scene, fidelity) in [
        ("harbour-50n", "gyroscopic"),
        ("harbour-50n", "full"),
        ("rolling-intercardinal", "gyroscopic"),
        ("three-gyro-harbour-50n", "gyroscopic"),
    ] {
        let ov = SceneOverrides {
            fidelity: Some(fidelity.parse().expect("fidelity")),
            ..Default::default()
        };
        let sim = Simulation::new(&Scene::load(scene, &ov).expect("scene")).expect("compiles");
        let m = &sim.model;
        let x = m.x0.clone();
        let mut dx = vec![0.0; x.len()];
        let mut jac = vec![0.0; x.len() * x.len()];
        m.rhs(0.0, &x, &mut dx);
        m.jacobian(0.0, &x, &mut jac);
        let before = ALLOCATIONS.with(Cell::get);
        for k in 0..200 {
            let t = k as f64 * 0.37;
            assert!(m.rhs(t, &x, &mut dx));
            m.jacobian(t, &x, &mut jac);
        }
        let made = ALLOCATIONS.with(Cell::get) - before;
        assert_eq!(
            made, 0,
            "{scene}/{fidelity}: {made} allocations in 200 evaluations"
        );
    }
}
