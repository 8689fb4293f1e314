//! RODAS4 (Hairer–Wanner, Solving ODE II, §VI.4; Fortran RODAS, METH = 1): a 6-stage,
//! order-4(3), stiffly accurate and L-stable Rosenbrock method. It lets the `full` models step
//! over fast, lightly damped nutation with steps set by the slow motion.
//!
//! The step, its error estimate (the 6th stage: 4th order minus the embedded 3rd), Gustafsson's
//! controller (exponent 1/4) and the Jacobian's handling are `rosenbrock`'s; here is only the
//! tableau, with RODAS's digits. Dense output is RODAS's 3rd-order continuous extension, so on the
//! engine's linear Anschütz a sample between step ends is 1.5–1.9× as far off as the step ends
//! (`docs/accuracy.md`).

use super::rosenbrock::{Method, Tableau, Z, row};

pub(crate) struct Rodas4;

impl Method for Rodas4 {
    const TABLEAU: Tableau = Tableau {
        stages: 6,
        tail: 5,
        gamma: GAMMA,
        a: [
            Z,
            row(&[A21]),
            row(&[A31, A32]),
            row(&[A41, A42, A43]),
            row(&[A51, A52, A53, A54]),
            Z,
            Z,
            Z,
        ],
        c: [
            Z,
            row(&[C21]),
            row(&[C31, C32]),
            row(&[C41, C42, C43]),
            row(&[C51, C52, C53, C54]),
            row(&[C61, C62, C63, C64, C65]),
            Z,
            Z,
        ],
        alpha: row(&[0.0, C2, C3, C4, 1.0, 1.0]),
        d: row(&[D1, D2, D3, D4, 0.0, 0.0]),
        dense: [
            row(&[D21, D22, D23, D24, D25]),
            row(&[D31, D32, D33, D34, D35]),
            Z,
        ],
        dense_rows: 2,
        dense_stages: 5,
        order: 4,
    };
}

const C2: f64 = 0.386;
const C3: f64 = 0.21;
const C4: f64 = 0.63;
const D1: f64 = 0.25;
const D2: f64 = -0.1043;
const D3: f64 = 0.1035;
const D4: f64 = -0.362_000_000_000_000_02e-1;
const A21: f64 = 0.1544000000000000e+01;
const A31: f64 = 0.9466785280815826;
const A32: f64 = 0.2557011698983284;
const A41: f64 = 0.3314825187068521e+01;
const A42: f64 = 0.2896124015972201e+01;
const A43: f64 = 0.9986419139977817;
const A51: f64 = 0.1221224509226641e+01;
const A52: f64 = 0.6019134481288629e+01;
const A53: f64 = 0.1253708332932087e+02;
const A54: f64 = -0.6878860361058950;
const C21: f64 = -0.5668800000000000e+01;
const C31: f64 = -0.2430093356833875e+01;
const C32: f64 = -0.2063599157091915;
const C41: f64 = -0.1073529058151375;
const C42: f64 = -0.9594562251023355e+01;
const C43: f64 = -0.2047028614809616e+02;
const C51: f64 = 0.7496443313967647e+01;
const C52: f64 = -0.1024680431464352e+02;
const C53: f64 = -0.3399990352819905e+02;
const C54: f64 = 0.1170890893206160e+02;
const C61: f64 = 0.8083246795921522e+01;
const C62: f64 = -0.7981132988064893e+01;
const C63: f64 = -0.3152159432874371e+02;
const C64: f64 = 0.1631930543123136e+02;
const C65: f64 = -0.6058818238834054e+01;
const GAMMA: f64 = 0.25;
const D21: f64 = 0.1012623508344586e+02;
const D22: f64 = -0.7487995877610167e+01;
const D23: f64 = -0.3480091861555747e+02;
const D24: f64 = -0.7992771707568823e+01;
const D25: f64 = 0.1025137723295662e+01;
const D31: f64 = -0.6762803392801253;
const D32: f64 = 0.6087714651680015e+01;
const D33: f64 = 0.1643084320892478e+02;
const D34: f64 = 0.2476722511418386e+02;
const D35: f64 = -0.6594389125716872e+01;
