//! The compiled equations: the right-hand side of one compiled model recorded once as a
//! straight-line program (a tape) and evaluated from it at every step.
//!
//! The engine is generic over [`Real`]; run on the recording scalar [`Tr`] it writes down every
//! arithmetic operation instead of doing it. Recording folds what a scene fixes (constants,
//! multiplications by 0 and 1, a stationary base's rotation and gravity), shares common
//! subexpressions, and drops what no output uses; what is left is the model's own equations with
//! none of the chain walk's bookkeeping. The exact Jacobian is recorded the same way, from the
//! engine run on dual numbers over the recording scalar, [`JET_WIDTH`] state directions a tape:
//! derivatives that are structurally zero fold away, so the Jacobian tape holds only the
//! chain-rule terms that can be nonzero, and a solve's derivative is recorded as solves with the
//! values' matrix (`Jet::record_solve`). Both run on plain `f64`.
//!
//! Exact, not approximate: the tape performs the same IEEE operations on the same operands in
//! the same order as the generic engine (folding evaluates them once, at recording; `x·1`,
//! `x + 0` and `0·x` are identities up to the sign of zero), so its results equal the engine's
//! to the last bit; `tests/tape.rs` holds it to that on every shipped scene.
//!
//! Straight-line is possible because the engine branches on values in one place only: the
//! pivot search of its dense solves. A solve is therefore recorded as one operation (matrix and
//! right-hand side in, solution out) and performed at evaluation by the same elimination.
//! Structural-zero tests (`x != 0` to skip a term) compare nodes: only a folded constant zero
//! is zero, so the tape keeps every term that is not zero for every state.
//!
//! A tape is an interpreter's program: each operation costs a dispatch, two loads and a store,
//! several times a native one, so a tape pays only where folding removed most of the engine's
//! work. The model runs a tape only where it pays: the right-hand side's by a timing at compile
//! (it equals the engine to the bit, so the choice cannot change a run), the Jacobian's by the
//! ratio of what the engine performs (`Tape::raw_len`, counted while recording) to what the tape
//! keeps (`Tape::len`); see `rhs_tape_pays` and `jacobian_tape_pays` in `model.rs` and the
//! measurement behind them, `benches/handwritten.rs`. Native code pays everywhere: the shipped
//! designs' tapes are also compiled ahead of time (`crate::native`), and a tape whose shape has
//! native code runs it instead of the interpreter (no JIT: no `unsafe` in this workspace).
//!
//! Recording uses a thread-local recorder (a [`Tr`] is a node number); evaluation uses a
//! thread-local slot buffer that grows once, so evaluating allocates nothing after the first
//! call on a thread.

use crate::dual::Real;
use crate::linalg;
use crate::reference_engine::MAX_COORDINATES;
use rustc_hash::FxHashMap;
use std::cell::RefCell;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// One recorded operation. Operands are node numbers while recording and slot numbers in a
/// finished [`Tape`].
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Const(f64),
    Input(u32),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Sin(u32),
    Cos(u32),
    Sqrt(u32),
    Atan2(u32, u32),
    Asin(u32),
    /// Component `k` of the solution of dense solve `s` (recording only; a tape has one
    /// [`Op::Solve`] writing all components to consecutive slots).
    SolveOut(u32, u32),
    /// Dense solve `s`: writes its n solution components to this slot and the n − 1 after.
    Solve(u32),
    // Fused forms (tapes only): a product used once, by a sum or difference, is computed where
    // it is used. Two roundings each, as unfused: `x·y + c` is not an FMA.
    /// x·y + c
    MulAdd(u32, u32, u32),
    /// x·y − c
    MulSub(u32, u32, u32),
    /// c − x·y
    SubMul(u32, u32, u32),
    /// x·y + z·w
    MulMulAdd(u32, u32, u32, u32),
    /// x·y − z·w
    MulMulSub(u32, u32, u32, u32),
}

/// A recorded dense solve A x = b of the leading n×n block.
#[derive(Clone, Debug)]
struct SolveSpec {
    n: usize,
    /// Symmetric positive definite first (LDLᵀ), pivoted elimination if that fails: what the
    /// engine does with a chain's own mass matrix.
    spd_first: bool,
    /// A row-major (n×n), then b (n): node or slot numbers.
    a: Vec<u32>,
    b: Vec<u32>,
}

#[derive(Default)]
struct Recorder {
    ops: Vec<Op>,
    values: Vec<f64>,
    /// Operations by identity, for sharing. Fx, not std's SipHash: the keys are node numbers
    /// the engine makes, not input an attacker chooses, and SipHash was ≈ 30 % of recording.
    shared: FxHashMap<OpKey, u32>,
    solves: Vec<SolveSpec>,
    /// Arithmetic the engine itself performs (every operation asked for, before folding and
    /// sharing; a solve by its elimination's count): what the tape is weighed against.
    raw: usize,
}

/// Hashable identity of an operation (constants by their bits).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct OpKey(u8, u64, u32);

impl OpKey {
    fn of(op: Op) -> Option<OpKey> {
        Some(match op {
            Op::Const(c) => OpKey(0, c.to_bits(), 0),
            Op::Input(i) => OpKey(1, i as u64, 0),
            // Addition and multiplication are commutative in IEEE arithmetic: one key.
            Op::Add(a, b) => OpKey(2, a.min(b) as u64, a.max(b)),
            Op::Sub(a, b) => OpKey(3, a as u64, b),
            Op::Mul(a, b) => OpKey(4, a.min(b) as u64, a.max(b)),
            Op::Div(a, b) => OpKey(5, a as u64, b),
            Op::Neg(a) => OpKey(6, a as u64, 0),
            Op::Sin(a) => OpKey(7, a as u64, 0),
            Op::Cos(a) => OpKey(8, a as u64, 0),
            Op::Sqrt(a) => OpKey(9, a as u64, 0),
            Op::Atan2(a, b) => OpKey(10, a as u64, b),
            Op::Asin(a) => OpKey(11, a as u64, 0),
            Op::SolveOut(..)
            | Op::Solve(_)
            | Op::MulAdd(..)
            | Op::MulSub(..)
            | Op::SubMul(..)
            | Op::MulMulAdd(..)
            | Op::MulMulSub(..) => return None,
        })
    }
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
    static SLOTS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// State directions one Jacobian tape carries (directions that are structurally zero fold
/// away while recording, so a narrower model pays nothing for the width).
pub(crate) const JET_WIDTH: usize = 8;

fn with_recorder<R>(f: impl FnOnce(&mut Recorder) -> R) -> R {
    RECORDER.with(|r| {
        f(r.borrow_mut()
            .as_mut()
            .expect("a recording scalar used outside tape::record"))
    })
}

impl Recorder {
    fn is_const(&self, id: u32) -> Option<f64> {
        match self.ops[id as usize] {
            Op::Const(c) => Some(c),
            _ => None,
        }
    }

    /// Appends `op` (value `v`) unless an equal operation exists.
    fn push(&mut self, op: Op, v: f64) -> Tr {
        let id = self.ops.len() as u32;
        if let Some(key) = OpKey::of(op) {
            // One probe: an equal operation's node, or this one's, reserved.
            let shared = *self.shared.entry(key).or_insert(id);
            if shared != id {
                return Tr {
                    id: shared,
                    v: self.values[shared as usize],
                };
            }
        }
        self.ops.push(op);
        self.values.push(v);
        Tr { id, v }
    }

    fn constant(&mut self, c: f64) -> Tr {
        self.push(Op::Const(c), c)
    }

    /// A binary operation, folded when both operands are constants or one is an identity.
    fn binary(&mut self, op: fn(u32, u32) -> Op, a: Tr, b: Tr, v: f64) -> Tr {
        self.raw += 1;
        let (ca, cb) = (self.is_const(a.id), self.is_const(b.id));
        if ca.is_some() && cb.is_some() {
            return self.constant(v);
        }
        let o = op(a.id, b.id);
        match o {
            Op::Add(..) if cb == Some(0.0) => return a,
            Op::Add(..) if ca == Some(0.0) => return b,
            Op::Sub(..) if cb == Some(0.0) => return a,
            Op::Sub(..) if ca == Some(0.0) => return self.unary(Op::Neg, b, v),
            Op::Sub(..) if a.id == b.id => return self.constant(v),
            Op::Mul(..) if ca == Some(0.0) || cb == Some(0.0) => return self.constant(0.0),
            Op::Mul(..) if cb == Some(1.0) => return a,
            Op::Mul(..) if ca == Some(1.0) => return b,
            Op::Mul(..) if cb == Some(-1.0) => return self.unary(Op::Neg, a, v),
            Op::Mul(..) if ca == Some(-1.0) => return self.unary(Op::Neg, b, v),
            Op::Div(..) if cb == Some(1.0) => return a,
            Op::Div(..) if ca == Some(0.0) => return self.constant(0.0),
            _ => {}
        }
        self.push(o, v)
    }

    fn unary(&mut self, op: fn(u32) -> Op, a: Tr, v: f64) -> Tr {
        self.raw += 1;
        if self.is_const(a.id).is_some() {
            return self.constant(v);
        }
        let o = op(a.id);
        if let (Op::Neg(_), Op::Neg(inner)) = (o, self.ops[a.id as usize]) {
            return Tr {
                id: inner,
                v: self.values[inner as usize],
            };
        }
        self.push(o, v)
    }
}

/// The recording scalar: a node of the tape being recorded, with its value at the recording
/// state (the engine may read values; only the solves' pivoting does, and solves are recorded
/// whole).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tr {
    id: u32,
    v: f64,
}

/// Nodes are equal when they are the same node: `x != 0` holds unless x is folded to zero.
impl PartialEq for Tr {
    fn eq(&self, o: &Self) -> bool {
        self.id == o.id
    }
}

macro_rules! binary_ops {
    ($($tr:ident $f:ident $tra:ident $fa:ident $op:ident $sym:tt;)*) => {$(
        impl $tr for Tr {
            type Output = Tr;
            fn $f(self, o: Tr) -> Tr {
                with_recorder(|r| r.binary(Op::$op, self, o, self.v $sym o.v))
            }
        }
        impl $tr<f64> for Tr {
            type Output = Tr;
            fn $f(self, o: f64) -> Tr {
                with_recorder(|r| {
                    let c = r.constant(o);
                    r.binary(Op::$op, self, c, self.v $sym o)
                })
            }
        }
        impl $tra for Tr {
            fn $fa(&mut self, o: Tr) {
                *self = *self $sym o;
            }
        }
    )*};
}

binary_ops! {
    Add add AddAssign add_assign Add +;
    Sub sub SubAssign sub_assign Sub -;
    Mul mul MulAssign mul_assign Mul *;
}

impl Div for Tr {
    type Output = Tr;
    fn div(self, o: Tr) -> Tr {
        with_recorder(|r| r.binary(Op::Div, self, o, self.v / o.v))
    }
}

impl Div<f64> for Tr {
    type Output = Tr;
    fn div(self, o: f64) -> Tr {
        with_recorder(|r| {
            let c = r.constant(o);
            r.binary(Op::Div, self, c, self.v / o)
        })
    }
}

impl Neg for Tr {
    type Output = Tr;
    fn neg(self) -> Tr {
        with_recorder(|r| r.unary(Op::Neg, self, -self.v))
    }
}

impl Real for Tr {
    fn cst(x: f64) -> Self {
        with_recorder(|r| r.constant(x))
    }
    fn re(&self) -> f64 {
        self.v
    }
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = crate::dual::sin_cos(self.v);
        with_recorder(|r| (r.unary(Op::Sin, self, s), r.unary(Op::Cos, self, c)))
    }
    fn sqrt(self) -> Self {
        with_recorder(|r| r.unary(Op::Sqrt, self, self.v.sqrt()))
    }
    fn atan2(self, x: Self) -> Self {
        with_recorder(|r| r.binary(Op::Atan2, self, x, self.v.atan2(x.v)))
    }
    fn asin(self) -> Self {
        with_recorder(|r| r.unary(Op::Asin, self, self.v.asin()))
    }

    fn record_solve<const N: usize>(
        a: &[[Self; N]; N],
        b: &mut [Self; N],
        n: usize,
        spd_first: bool,
    ) -> Option<bool> {
        if let Some(solved) = Self::solve_constant(a, b, n, spd_first) {
            return Some(solved);
        }
        // The values at the recording state, by the same solves the tape will run.
        let mut av = [[0.0; N]; N];
        let mut bv = [0.0; N];
        for i in 0..n {
            bv[i] = b[i].v;
            for j in 0..n {
                av[i][j] = a[i][j].v;
            }
        }
        solve_values(&mut av, &mut bv, n, spd_first);
        with_recorder(|r| {
            // Elimination and substitution: n³/3 + n² multiply-adds.
            r.raw += 2 * (n * n * n / 3 + n * n);
            let s = r.solves.len() as u32;
            r.solves.push(SolveSpec {
                n,
                spd_first,
                a: (0..n * n).map(|k| a[k / n][k % n].id).collect(),
                b: (0..n).map(|i| b[i].id).collect(),
            });
            for k in 0..n {
                b[k] = r.push(Op::SolveOut(s, k as u32), bv[k]);
            }
        });
        Some(true)
    }
}

impl Tr {
    /// A solve whose matrix is constant (a one-coordinate chain's mass matrix: Foucault's
    /// gyroscopes) is factored while recording: the engine's own elimination runs on the
    /// recording scalars, its factor folds to constants and only the substitution on b is
    /// recorded: the same operations in the same order as the engine's, so the tape keeps its
    /// results to the bit and drops the factor's divisions and checks from every evaluation.
    /// `None` if the matrix is not constant, or singular (then recorded as a solve, which
    /// reports it at every evaluation as before).
    fn solve_constant<const N: usize>(
        a: &[[Self; N]; N],
        b: &mut [Self; N],
        n: usize,
        spd_first: bool,
    ) -> Option<bool> {
        let constant =
            with_recorder(|r| (0..n * n).all(|k| r.is_const(a[k / n][k % n].id).is_some()));
        if !constant {
            return None;
        }
        let raw = with_recorder(|r| r.raw);
        let mut x = *b;
        // LDLᵀ leaves b untouched when it fails, as the engine's fallback expects.
        let solved = (spd_first && linalg::ldlt_nested(a, &mut x, n))
            || linalg::eliminate_nested(&mut { *a }, &mut x, n);
        // Count the engine's work as for a recorded solve: the tape is weighed against it.
        with_recorder(|r| r.raw = raw + 2 * (n * n * n / 3 + n * n));
        solved.then(|| {
            *b = x;
            true
        })
    }
}

/// The engine's dense solve on any scalar (LDLᵀ first when asked, as the engine does for a
/// mass matrix, pivoted elimination otherwise or if that fails). False if singular.
pub(crate) fn solve_values<T: Real, const N: usize>(
    a: &mut [[T; N]; N],
    b: &mut [T; N],
    n: usize,
    spd_first: bool,
) -> bool {
    (spd_first && linalg::solve_spd_nested(a, b, n)) || linalg::solve_nested(a, b, n)
}

/// A recorded right-hand side (or any function of `n_inputs` scalars), ready to evaluate.
#[derive(Clone, Debug)]
pub(crate) struct Tape {
    /// Values of the first slots.
    consts: Vec<f64>,
    n_inputs: usize,
    /// One per slot after the constants and inputs (a solve fills n slots; the n − 1 after its
    /// own hold no operation and are skipped by the count in `SolveSpec`).
    ops: Vec<Op>,
    solves: Vec<SolveSpec>,
    /// Slots of the outputs.
    outputs: Vec<u32>,
    n_slots: usize,
    /// The operations the engine performs for the same outputs (see `Recorder::raw`).
    raw_ops: usize,
    /// Fingerprint of everything but the constants' values ([`Tape::shape`]).
    shape: u64,
    /// Native code generated ahead of time for a tape of this shape, if any (`crate::native`).
    native: Option<NativeFn>,
}

/// A tape compiled to Rust ahead of time: (constants, inputs, outputs) → false if a solve is
/// singular. Same operations, same order, same operands as the tape it was generated from.
pub(crate) type NativeFn = fn(&[f64], &[f64], &mut [f64]) -> bool;

/// Runs `f` (a recording) on a thread with a large stack: the engine keeps its dual-number
/// matrices on the stack, and over the recording scalar (16 bytes, and 9 of them in a Jacobian
/// direction block) they outgrow the 2 MB a spawned thread gets by default.
pub(crate) fn on_large_stack<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("tape recording".into())
            .stack_size(256 << 20)
            .spawn_scoped(s, f)
            .expect("a thread for tape recording")
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e))
    })
}

/// Records `f` on `n_inputs` recording scalars taking the values `at` (used only to keep the
/// recording's own values meaningful) and returns its tape. `f` writes its outputs and returns
/// false if it cannot be evaluated at `at`.
pub(crate) fn record(at: &[f64], n_outputs: usize, f: impl FnOnce(&[Tr], &mut [Tr])) -> Tape {
    let previous = RECORDER.with(|r| r.borrow_mut().replace(Recorder::default()));
    assert!(previous.is_none(), "tape recordings do not nest");
    let inputs: Vec<Tr> = with_recorder(|r| {
        at.iter()
            .enumerate()
            .map(|(i, &v)| r.push(Op::Input(i as u32), v))
            .collect()
    });
    let zero = with_recorder(|r| r.constant(0.0));
    let mut outputs = vec![zero; n_outputs];
    f(&inputs, &mut outputs);
    let rec = RECORDER
        .with(|r| r.borrow_mut().take())
        .expect("the recorder is still installed");
    let raw = rec.raw;
    let mut tape = Tape {
        raw_ops: raw,
        ..compact(rec, at.len(), &outputs)
    };
    tape.shape = tape.fingerprint();
    tape.native = crate::native::lookup(tape.shape, tape.ops.len());
    tape
}

/// The live products used exactly once, by a sum or a difference: those are computed inside
/// their user (`Op::MulAdd` and kin), one dispatch instead of two, same roundings.
fn fusable_products(
    rec: &Recorder,
    live: &[bool],
    solve_live: &[bool],
    outputs: &[Tr],
) -> Vec<bool> {
    const ELSEWHERE: u32 = u32::MAX;
    let n = rec.ops.len();
    let mut uses = vec![0u32; n];
    let mut user = vec![ELSEWHERE; n];
    let mut used_by = |x: u32, by: u32| {
        uses[x as usize] += 1;
        user[x as usize] = by;
    };
    for o in outputs {
        used_by(o.id, ELSEWHERE);
    }
    for (s, spec) in rec.solves.iter().enumerate() {
        if solve_live[s] {
            for &x in spec.a.iter().chain(&spec.b) {
                used_by(x, ELSEWHERE);
            }
        }
    }
    for id in (0..n).filter(|&id| live[id]) {
        for x in rec.ops[id].arithmetic_operands() {
            used_by(x, id as u32);
        }
    }
    (0..n)
        .map(|id| {
            live[id]
                && matches!(rec.ops[id], Op::Mul(..))
                && uses[id] == 1
                && user[id] != ELSEWHERE
                && matches!(rec.ops[user[id] as usize], Op::Add(..) | Op::Sub(..))
        })
        .collect()
}

/// The live constants' slots, numbered by first use (operations in recording order, then the
/// solves' operands as their first component is met, then the outputs), and their values; every
/// other node's slot is left unset (`u32::MAX`). Not by recording order: constants are shared by
/// value, so a constant's recording order depends on whether an equal value was recorded earlier
/// (even by dead work), and with it the shape. Numbered by use, two recordings of the same
/// arithmetic have one shape whatever the coincidences before it.
fn number_constants(rec: &Recorder, live: &[bool], outputs: &[Tr]) -> (Vec<u32>, Vec<f64>) {
    let n = rec.ops.len();
    let mut slot = vec![u32::MAX; n];
    let mut consts = Vec::new();
    let mut number = |x: u32| {
        if let Op::Const(c) = rec.ops[x as usize]
            && slot[x as usize] == u32::MAX
        {
            slot[x as usize] = consts.len() as u32;
            consts.push(c);
        }
    };
    let mut solve_seen = vec![false; rec.solves.len()];
    for id in (0..n).filter(|&id| live[id]) {
        let op = rec.ops[id];
        op.arithmetic_operands().for_each(&mut number);
        if let Op::SolveOut(sv, _) = op
            && !solve_seen[sv as usize]
        {
            solve_seen[sv as usize] = true;
            let spec = &rec.solves[sv as usize];
            spec.a.iter().chain(&spec.b).for_each(|&x| number(x));
        }
    }
    outputs.iter().for_each(|o| number(o.id));
    (slot, consts)
}

/// Drops dead nodes and numbers slots: constants (by first use), inputs, then operations in
/// recording order.
fn compact(rec: Recorder, n_inputs: usize, outputs: &[Tr]) -> Tape {
    let n = rec.ops.len();
    let mut live = vec![false; n];
    let mut solve_live = vec![false; rec.solves.len()];
    for o in outputs {
        live[o.id as usize] = true;
    }
    for id in (0..n).rev() {
        if !live[id] {
            continue;
        }
        let mut mark = |x: u32| live[x as usize] = true;
        match rec.ops[id] {
            Op::Const(_) | Op::Input(_) | Op::Solve(_) => {}
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) | Op::Atan2(a, b) => {
                mark(a);
                mark(b);
            }
            Op::Neg(a) | Op::Sin(a) | Op::Cos(a) | Op::Sqrt(a) | Op::Asin(a) => mark(a),
            Op::MulAdd(..)
            | Op::MulSub(..)
            | Op::SubMul(..)
            | Op::MulMulAdd(..)
            | Op::MulMulSub(..) => {
                unreachable!("fused forms are made by compact, not recorded")
            }
            Op::SolveOut(s, _) => {
                if !solve_live[s as usize] {
                    solve_live[s as usize] = true;
                    let spec = &rec.solves[s as usize];
                    for &x in spec.a.iter().chain(&spec.b) {
                        live[x as usize] = true;
                    }
                }
            }
        }
    }
    // Every component of a live solve gets its slot (the solve writes them all).
    for id in 0..n {
        if let Op::SolveOut(s, _) = rec.ops[id]
            && solve_live[s as usize]
        {
            live[id] = true;
        }
    }
    let fused = fusable_products(&rec, &live, &solve_live, outputs);
    let (mut slot, consts) = number_constants(&rec, &live, outputs);
    let base = consts.len();
    for id in 0..n {
        if let Op::Input(i) = rec.ops[id] {
            slot[id] = (base + i as usize) as u32;
        }
    }
    let mut next = base + n_inputs;
    let mut ops = Vec::new();
    let mut solves = Vec::new();
    let mut solve_slot = vec![u32::MAX; rec.solves.len()];
    for id in 0..n {
        if !live[id] {
            continue;
        }
        if fused[id] {
            continue; // computed where it is used
        }
        let op = rec.ops[id];
        let s = |x: u32| slot[x as usize];
        // The factors of operand `x` if it is a product fused into this operation.
        let product = |x: u32| match rec.ops[x as usize] {
            Op::Mul(p, q) if fused[x as usize] => Some((s(p), s(q))),
            _ => None,
        };
        let mapped = match op {
            Op::Const(_) | Op::Input(_) | Op::Solve(_) => continue,
            Op::Add(a, b) => match (product(a), product(b)) {
                (Some((x, y)), Some((z, w))) => Op::MulMulAdd(x, y, z, w),
                (Some((x, y)), None) => Op::MulAdd(x, y, s(b)),
                // c + x·y = x·y + c exactly: IEEE addition commutes.
                (None, Some((x, y))) => Op::MulAdd(x, y, s(a)),
                (None, None) => Op::Add(s(a), s(b)),
            },
            Op::Sub(a, b) => match (product(a), product(b)) {
                (Some((x, y)), Some((z, w))) => Op::MulMulSub(x, y, z, w),
                (Some((x, y)), None) => Op::MulSub(x, y, s(b)),
                (None, Some((x, y))) => Op::SubMul(s(a), x, y),
                (None, None) => Op::Sub(s(a), s(b)),
            },
            Op::Mul(a, b) => Op::Mul(s(a), s(b)),
            Op::Div(a, b) => Op::Div(s(a), s(b)),
            Op::Atan2(a, b) => Op::Atan2(s(a), s(b)),
            Op::Neg(a) => Op::Neg(s(a)),
            Op::Sin(a) => Op::Sin(s(a)),
            Op::Cos(a) => Op::Cos(s(a)),
            Op::Sqrt(a) => Op::Sqrt(s(a)),
            Op::Asin(a) => Op::Asin(s(a)),
            Op::MulAdd(..)
            | Op::MulSub(..)
            | Op::SubMul(..)
            | Op::MulMulAdd(..)
            | Op::MulMulSub(..) => {
                unreachable!("fused forms are made here, not recorded")
            }
            Op::SolveOut(sv, k) => {
                if k == 0 {
                    let spec = &rec.solves[sv as usize];
                    solve_slot[sv as usize] = next as u32;
                    solves.push(SolveSpec {
                        n: spec.n,
                        spd_first: spec.spd_first,
                        a: spec.a.iter().map(|&x| s(x)).collect(),
                        b: spec.b.iter().map(|&x| s(x)).collect(),
                    });
                    ops.push(Op::Solve(solves.len() as u32 - 1));
                    next += spec.n;
                }
                slot[id] = solve_slot[sv as usize] + k;
                continue;
            }
        };
        slot[id] = next as u32;
        ops.push(mapped);
        next += 1;
    }
    Tape {
        consts,
        n_inputs,
        ops,
        solves,
        outputs: outputs.iter().map(|o| slot[o.id as usize]).collect(),
        n_slots: next,
        raw_ops: 0,
        shape: 0,
        native: None,
    }
}

impl Tape {
    /// Operations after folding and dead-code removal (a solve counts one).
    pub(crate) fn len(&self) -> usize {
        self.ops.len()
    }

    /// The operations the generic engine performs for the same outputs.
    pub(crate) fn raw_len(&self) -> usize {
        self.raw_ops
    }

    /// Evaluates the tape at `inputs` into `out`, in `slots` (resized as needed). False if a
    /// solve is singular there.
    fn run<T: Real>(&self, slots: &mut Vec<T>, inputs: &[T], out: &mut [T]) -> bool {
        debug_assert_eq!(inputs.len(), self.n_inputs);
        slots.resize(self.n_slots, T::zero());
        let nc = self.consts.len();
        for (s, &c) in slots.iter_mut().zip(&self.consts) {
            *s = T::cst(c);
        }
        slots[nc..nc + self.n_inputs].copy_from_slice(inputs);
        let mut k = nc + self.n_inputs;
        for op in &self.ops {
            let s = &*slots;
            let v = match *op {
                Op::Add(a, b) => s[a as usize] + s[b as usize],
                Op::Sub(a, b) => s[a as usize] - s[b as usize],
                Op::Mul(a, b) => s[a as usize] * s[b as usize],
                Op::Div(a, b) => s[a as usize] / s[b as usize],
                Op::Neg(a) => -s[a as usize],
                Op::Sin(a) => s[a as usize].sin(),
                Op::Cos(a) => s[a as usize].cos(),
                Op::Sqrt(a) => s[a as usize].sqrt(),
                Op::Atan2(a, b) => s[a as usize].atan2(s[b as usize]),
                Op::Asin(a) => s[a as usize].asin(),
                Op::MulAdd(x, y, c) => s[x as usize] * s[y as usize] + s[c as usize],
                Op::MulSub(x, y, c) => s[x as usize] * s[y as usize] - s[c as usize],
                Op::SubMul(c, x, y) => s[c as usize] - s[x as usize] * s[y as usize],
                Op::MulMulAdd(x, y, z, w) => {
                    s[x as usize] * s[y as usize] + s[z as usize] * s[w as usize]
                }
                Op::MulMulSub(x, y, z, w) => {
                    s[x as usize] * s[y as usize] - s[z as usize] * s[w as usize]
                }
                Op::Solve(i) => {
                    let spec = &self.solves[i as usize];
                    if !self.solve(spec, slots, k) {
                        return false;
                    }
                    k += spec.n;
                    continue;
                }
                Op::Const(_) | Op::Input(_) | Op::SolveOut(..) => unreachable!("not in a tape"),
            };
            slots[k] = v;
            k += 1;
        }
        for (o, &s) in out.iter_mut().zip(&self.outputs) {
            *o = slots[s as usize];
        }
        true
    }

    /// A solve on arrays just large enough (zeroing a 15×15 array of dual numbers would cost
    /// more than a small solve itself).
    fn solve<T: Real>(&self, spec: &SolveSpec, slots: &mut [T], at: usize) -> bool {
        match spec.n {
            1 => self.solve_n::<T, 1>(spec, slots, at),
            2 => self.solve_n::<T, 2>(spec, slots, at),
            3 => self.solve_n::<T, 3>(spec, slots, at),
            4 => self.solve_n::<T, 4>(spec, slots, at),
            5..=6 => self.solve_n::<T, 6>(spec, slots, at),
            7..=8 => self.solve_n::<T, 8>(spec, slots, at),
            9..=11 => self.solve_n::<T, 11>(spec, slots, at),
            _ => self.solve_n::<T, MAX_COORDINATES>(spec, slots, at),
        }
    }

    fn solve_n<T: Real, const N: usize>(
        &self,
        spec: &SolveSpec,
        slots: &mut [T],
        at: usize,
    ) -> bool {
        let n = spec.n;
        let mut a = [[T::zero(); N]; N];
        let mut b = [T::zero(); N];
        for i in 0..n {
            b[i] = slots[spec.b[i] as usize];
            for j in 0..n {
                a[i][j] = slots[spec.a[i * n + j] as usize];
            }
        }
        if !solve_values(&mut a, &mut b, n, spec.spd_first) {
            return false;
        }
        slots[at..at + n].copy_from_slice(&b[..n]);
        true
    }

    /// The outputs at `inputs` (f64), by native code if this shape has some, by the
    /// interpreter otherwise (the same to the bit). False if a solve is singular there.
    pub(crate) fn eval(&self, inputs: &[f64], out: &mut [f64]) -> bool {
        match self.native {
            Some(f) => f(&self.consts, inputs, out),
            None => self.interpret(inputs, out),
        }
    }

    /// The outputs at `inputs` by the interpreter, whether or not native code exists.
    pub(crate) fn interpret(&self, inputs: &[f64], out: &mut [f64]) -> bool {
        SLOTS.with(|s| self.run(&mut s.borrow_mut(), inputs, out))
    }

    /// Whether the tape performs a dense solve.
    pub(crate) fn has_solve(&self) -> bool {
        !self.solves.is_empty()
    }

    /// Whether this tape runs as native code generated ahead of time.
    pub(crate) fn is_native(&self) -> bool {
        self.native.is_some()
    }

    /// Fingerprint of the tape's structure: operations, operands, solves, outputs and the
    /// counts of constants and inputs, not the constants' values. Two tapes of one shape run
    /// the same native code on their own constants (a design's numbers or a latitude change
    /// the values, not the shape; a value that folds, such as a zero, changes the shape).
    pub(crate) fn shape(&self) -> u64 {
        self.shape
    }

    /// FNV-1a over the structure, in 64-bit words (stable across builds and platforms, unlike
    /// the standard library's hasher).
    fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |w: u64| {
            for byte in w.to_le_bytes() {
                h ^= byte as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for n in [
            self.consts.len(),
            self.n_inputs,
            self.n_slots,
            self.ops.len(),
        ] {
            eat(n as u64);
        }
        for op in &self.ops {
            let (kind, operands) = op.parts();
            eat(kind);
            for x in operands {
                eat(x as u64);
            }
        }
        for spec in &self.solves {
            eat(spec.n as u64);
            eat(spec.spd_first as u64);
            for &x in spec.a.iter().chain(&spec.b) {
                eat(x as u64);
            }
        }
        eat(self.outputs.len() as u64);
        for &o in &self.outputs {
            eat(o as u64);
        }
        h
    }

    /// The tape as a Rust function named `name` with the [`NativeFn`] signature: one `let` per
    /// operation, in the tape's order, on the same operands (what `crate::native` holds).
    pub(crate) fn rust_source(&self, name: &str) -> String {
        use std::fmt::Write;
        let nc = self.consts.len();
        let ni = self.n_inputs;
        let slot = |s: u32| -> String {
            let s = s as usize;
            if s < nc {
                format!("c[{s}]")
            } else if s < nc + ni {
                format!("x[{}]", s - nc)
            } else {
                format!("v{s}")
            }
        };
        let mut src = String::new();
        let w = &mut src;
        let _ = writeln!(
            w,
            "/// {} operations ({} by the engine).\npub(super) fn {name}(c: &[f64], x: &[f64], out: &mut [f64]) -> bool {{",
            self.ops.len(),
            self.raw_ops
        );
        let no = self.outputs.len();
        let _ = writeln!(
            w,
            "    let c: &[f64; {nc}] = c.try_into().expect(\"{nc} constants\");"
        );
        let _ = writeln!(
            w,
            "    let x: &[f64; {ni}] = x.try_into().expect(\"{ni} inputs\");"
        );
        let _ = writeln!(
            w,
            "    let out: &mut [f64; {no}] = out.try_into().expect(\"{no} outputs\");"
        );
        let mut k = nc + ni;
        let mut ops = self.ops.iter().peekable();
        while let Some(op) = ops.next() {
            let e = |a: u32, b: u32, o: &str| format!("{} {o} {}", slot(a), slot(b));
            // The recorder writes sin and cos of one angle side by side: one call computes both
            // (the same bits as the two calls, see `dual::sin_cos`).
            if let (Op::Sin(a), Some(&&Op::Cos(b))) = (*op, ops.peek())
                && a == b
            {
                let _ = writeln!(w, "    let (v{k}, v{}) = libm::sincos({});", k + 1, slot(a));
                ops.next();
                k += 2;
                continue;
            }
            let expr = match *op {
                Op::Add(a, b) => e(a, b, "+"),
                Op::Sub(a, b) => e(a, b, "-"),
                Op::Mul(a, b) => e(a, b, "*"),
                Op::Div(a, b) => e(a, b, "/"),
                Op::Neg(a) => format!("-{}", slot(a)),
                Op::Sin(a) => format!("libm::sin({})", slot(a)),
                Op::Cos(a) => format!("libm::cos({})", slot(a)),
                Op::Sqrt(a) => format!("{}.sqrt()", slot(a)),
                Op::Atan2(a, b) => format!("{}.atan2({})", slot(a), slot(b)),
                Op::Asin(a) => format!("{}.asin()", slot(a)),
                Op::MulAdd(x, y, c) => format!("{} + {}", e(x, y, "*"), slot(c)),
                Op::MulSub(x, y, c) => format!("{} - {}", e(x, y, "*"), slot(c)),
                Op::SubMul(c, x, y) => format!("{} - {}", slot(c), e(x, y, "*")),
                Op::MulMulAdd(x, y, z, q) => format!("{} + {}", e(x, y, "*"), e(z, q, "*")),
                Op::MulMulSub(x, y, z, q) => format!("{} - {}", e(x, y, "*"), e(z, q, "*")),
                Op::Solve(i) => {
                    let spec = &self.solves[i as usize];
                    let n = spec.n;
                    let names: Vec<String> = (k..k + n).map(|s| format!("v{s}")).collect();
                    let rows: Vec<String> = (0..n)
                        .map(|r| {
                            let row: Vec<String> = spec.a[r * n..(r + 1) * n]
                                .iter()
                                .map(|&x| slot(x))
                                .collect();
                            format!("[{}]", row.join(", "))
                        })
                        .collect();
                    let b: Vec<String> = spec.b.iter().map(|&x| slot(x)).collect();
                    let _ = writeln!(
                        w,
                        "    let Some([{}]) = solve::<{n}>([{}], [{}], {}) else {{ return false }};",
                        names.join(", "),
                        rows.join(", "),
                        b.join(", "),
                        spec.spd_first
                    );
                    k += n;
                    continue;
                }
                Op::Const(_) | Op::Input(_) | Op::SolveOut(..) => unreachable!("not in a tape"),
            };
            let _ = writeln!(w, "    let v{k} = {expr};");
            k += 1;
        }
        for (i, &s) in self.outputs.iter().enumerate() {
            let _ = writeln!(w, "    out[{i}] = {};", slot(s));
        }
        let _ = writeln!(w, "    true\n}}");
        src
    }
}

impl Op {
    /// The recorded nodes an arithmetic operation reads (none for constants, inputs and solves).
    fn arithmetic_operands(self) -> impl Iterator<Item = u32> {
        let (ops, n) = match self {
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) | Op::Atan2(a, b) => {
                ([a, b], 2)
            }
            Op::Neg(a) | Op::Sin(a) | Op::Cos(a) | Op::Sqrt(a) | Op::Asin(a) => ([a, 0], 1),
            _ => ([0, 0], 0),
        };
        ops.into_iter().take(n)
    }

    /// A kind number and the operands, for fingerprints.
    fn parts(&self) -> (u64, Vec<u32>) {
        match *self {
            Op::Const(_) => (0, vec![]),
            Op::Input(i) => (1, vec![i]),
            Op::Add(a, b) => (2, vec![a, b]),
            Op::Sub(a, b) => (3, vec![a, b]),
            Op::Mul(a, b) => (4, vec![a, b]),
            Op::Div(a, b) => (5, vec![a, b]),
            Op::Neg(a) => (6, vec![a]),
            Op::Sin(a) => (7, vec![a]),
            Op::Cos(a) => (8, vec![a]),
            Op::Sqrt(a) => (9, vec![a]),
            Op::Atan2(a, b) => (10, vec![a, b]),
            Op::Asin(a) => (11, vec![a]),
            Op::SolveOut(s, k) => (12, vec![s, k]),
            Op::Solve(s) => (13, vec![s]),
            Op::MulAdd(x, y, c) => (14, vec![x, y, c]),
            Op::MulSub(x, y, c) => (15, vec![x, y, c]),
            Op::SubMul(c, x, y) => (16, vec![c, x, y]),
            Op::MulMulAdd(x, y, z, w) => (17, vec![x, y, z, w]),
            Op::MulMulSub(x, y, z, w) => (18, vec![x, y, z, w]),
        }
    }
}
