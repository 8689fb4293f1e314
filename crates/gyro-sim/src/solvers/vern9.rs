//! Verner's 9(8) pair ("most efficient", IIa): 16 stages, the 16th the embedded 8th-order
//! one, plus the derivative at the new point, which the next step starts from (16 rhs calls per
//! accepted step, 15 per rejected one); an order-9 continuous extension on 9 further stages,
//! made only in steps that contain an output sample. For tight tolerances on smooth problems,
//! where an order-9 method takes fewer rhs calls than DOP853 for the same achieved error
//! (`gyrolab accuracy`, docs/accuracy.md). The step controller is DOP853's (PI, beta = 0.04).
//!
//! Coefficients: J. H. Verner, "Numerically optimal Runge–Kutta pairs with interpolants",
//! Numer. Algorithms 53 (2010) 383–396, his 9(8) IIa pair and its order-9 interpolant, as
//! double-precision numbers (the values tabulated by SciML's OrdinaryDiffEq.jl, MIT). Stage
//! indices below are 0-based: stages 0..15 are the step's, 16 is f at the new point (its
//! coefficient row is b) and 17..25 the interpolant's. The unit tests below hold the rows to
//! their abscissae and the tables to the 486 order conditions up to order 9 (b, the embedded
//! weights to order 8, the interpolant at two points).

use super::{
    Attempt, InitialStepScratch, OdeSystem, PiController, SolveError, SolverStats, Stepper,
    Tolerances, Window, error_norm, initial_step, start_derivative,
};

const STAGES: usize = 26;
/// The stage holding f at the new point (the next step's stage 0).
const NEW: usize = 16;

/// Abscissae c_s.
const C: [f64; STAGES] = [
    0.0,
    0.03462,
    0.09702435063878045,
    0.14553652595817068,
    0.561,
    0.22900791159048503,
    0.544992088409515,
    0.645,
    0.48375,
    0.06757,
    0.25,
    0.6590650618730999,
    0.8206,
    0.9012,
    1.0,
    1.0,
    1.0,
    0.7404185470631561,
    0.888,
    0.696,
    0.487,
    0.025,
    0.15,
    0.32,
    0.78,
    0.96,
];

/// Stage coefficients a[s][j], j < s (rows 16..25: the interpolant's stages; row 16 is b).
const A: [[f64; STAGES]; STAGES] = {
    let mut a = [[0.0; STAGES]; STAGES];

    a[1][0] = 0.03462;

    a[2][0] = -0.03893354388572875;
    a[2][1] = 0.13595789452450918;

    a[3][0] = 0.03638413148954267;
    a[3][2] = 0.10915239446862801;

    a[4][0] = 2.0257639143939694;
    a[4][2] = -7.638023836496291;
    a[4][3] = 6.173259922102322;

    a[5][0] = 0.05112275589406061;
    a[5][3] = 0.17708237945550218;
    a[5][4] = 0.0008027762409222536;

    a[6][0] = 0.13160063579752163;
    a[6][3] = -0.2957276252669636;
    a[6][4] = 0.08781378035642955;
    a[6][5] = 0.6213052975225274;

    a[7][0] = 0.07166666666666667;
    a[7][5] = 0.33055335789153195;
    a[7][6] = 0.2427799754418014;

    a[8][0] = 0.071806640625;
    a[8][5] = 0.3294380283228177;
    a[8][6] = 0.1165190029271823;
    a[8][7] = -0.034013671875;

    a[9][0] = 0.04836757646340646;
    a[9][5] = 0.03928989925676164;
    a[9][6] = 0.10547409458903446;
    a[9][7] = -0.021438652846483126;
    a[9][8] = -0.10412291746271944;

    a[10][0] = -0.026645614872014785;
    a[10][5] = 0.03333333333333333;
    a[10][6] = -0.1631072244872467;
    a[10][7] = 0.03396081684127761;
    a[10][8] = 0.1572319413814626;
    a[10][9] = 0.21522674780318796;

    a[11][0] = 0.03689009248708622;
    a[11][5] = -0.1465181576725543;
    a[11][6] = 0.2242577768172024;
    a[11][7] = 0.02294405717066073;
    a[11][8] = -0.0035850052905728597;
    a[11][9] = 0.08669223316444385;
    a[11][10] = 0.43838406519683376;

    a[12][0] = -0.4866012215113341;
    a[12][5] = -6.304602650282853;
    a[12][6] = -0.2812456182894729;
    a[12][7] = -2.679019236219849;
    a[12][8] = 0.5188156639241577;
    a[12][9] = 1.3653531876033418;
    a[12][10] = 5.8850910885039465;
    a[12][11] = 2.8028087862720628;

    a[13][0] = 0.4185367457753472;
    a[13][5] = 6.724547581906459;
    a[13][6] = -0.42544428016461133;
    a[13][7] = 3.3432791530012653;
    a[13][8] = 0.6170816631175374;
    a[13][9] = -0.9299661239399329;
    a[13][10] = -6.099948804751011;
    a[13][11] = -3.002206187889399;
    a[13][12] = 0.2553202529443446;

    a[14][0] = -0.7793740861228848;
    a[14][5] = -13.937342538107776;
    a[14][6] = 1.2520488533793563;
    a[14][7] = -14.691500408016868;
    a[14][8] = -0.494705058533141;
    a[14][9] = 2.2429749091462368;
    a[14][10] = 13.367893803828643;
    a[14][11] = 14.396650486650687;
    a[14][12] = -0.79758133317768;
    a[14][13] = 0.4409353709534278;

    a[15][0] = 2.0580513374668867;
    a[15][5] = 22.357937727968032;
    a[15][6] = 0.9094981099755646;
    a[15][7] = 35.89110098240264;
    a[15][8] = -3.442515027624454;
    a[15][9] = -4.865481358036369;
    a[15][10] = -18.909803813543427;
    a[15][11] = -34.26354448030452;
    a[15][12] = 1.2647565216956427;

    a[16][0] = 0.014611976858423152;
    a[16][7] = -0.3915211862331339;
    a[16][8] = 0.23109325002895065;
    a[16][9] = 0.12747667699928525;
    a[16][10] = 0.2246434176204158;
    a[16][11] = 0.5684352689748513;
    a[16][12] = 0.058258715572158275;
    a[16][13] = 0.13643174034822156;
    a[16][14] = 0.030570139830827976;

    a[17][0] = 0.015499736681895594;
    a[17][7] = 0.3355153219059635;
    a[17][8] = 0.20036139441918607;
    a[17][9] = 0.12520606592835493;
    a[17][10] = 0.22986763931842066;
    a[17][11] = -0.20202506534761813;
    a[17][12] = 0.05917103230665457;
    a[17][13] = -0.026518347830476387;
    a[17][14] = -0.023840946021309713;
    a[17][16] = 0.027181715702085017;

    a[18][0] = 0.013024539431143383;
    a[18][7] = -0.7452850902413112;
    a[18][8] = 0.2643867896429301;
    a[18][9] = 0.1313961758372754;
    a[18][10] = 0.21672538151229273;
    a[18][11] = 0.8734117564076053;
    a[18][12] = 0.011859056439357767;
    a[18][13] = 0.05876002941689551;
    a[18][14] = 0.003266518630202088;
    a[18][16] = -0.00895930864841793;
    a[18][17] = 0.06941415157202692;

    a[19][0] = 0.013970899969259426;
    a[19][7] = -0.46657653359576745;
    a[19][8] = 0.24163727872162571;
    a[19][9] = 0.12903633413456747;
    a[19][10] = 0.22167006717351054;
    a[19][11] = 0.6257275123364645;
    a[19][12] = 0.04355312415679284;
    a[19][13] = 0.10119624916672908;
    a[19][14] = 0.01808582254679721;
    a[19][16] = -0.020798755876891697;
    a[19][17] = -0.09022232517086219;
    a[19][18] = -0.12127967356222542;

    a[20][0] = 0.016046388883181127;
    a[20][7] = 0.09517712399458336;
    a[20][8] = 0.13591872646553177;
    a[20][9] = 0.1237765280959854;
    a[20][10] = 0.2335656264102966;
    a[20][11] = -0.09051508172625873;
    a[20][12] = -0.02537574270006131;
    a[20][13] = -0.13596316968871622;
    a[20][14] = -0.04679214284145113;
    a[20][16] = 0.05177958859391748;
    a[20][17] = 0.09672595677476774;
    a[20][18] = 0.14773126903407427;
    a[20][19] = -0.11507507129585039;

    a[21][0] = 0.018029186238936207;
    a[21][7] = 0.06983601042028874;
    a[21][8] = -0.025412476607916634;
    a[21][9] = 0.008487827035463275;
    a[21][10] = -0.002427525516089802;
    a[21][11] = -0.10478397528938199;
    a[21][12] = -0.014731477952480419;
    a[21][13] = -0.03916338390816177;
    a[21][14] = -0.010056573432939595;
    a[21][16] = 0.011025103922048344;
    a[21][17] = 0.005092830749095398;
    a[21][18] = 0.04759715599420645;
    a[21][19] = 0.03386307003288383;
    a[21][20] = 0.02764422831404798;

    a[22][0] = 0.01677431640522778;
    a[22][7] = 0.6220437408820475;
    a[22][8] = -0.2060859809768842;
    a[22][9] = 0.11563949897660589;
    a[22][10] = 0.026641017933783588;
    a[22][11] = -0.937681079341877;
    a[22][12] = -0.13678064667021603;
    a[22][13] = -0.3678480995268297;
    a[22][14] = -0.09547871314402478;
    a[22][16] = 0.10134920184223697;
    a[22][17] = -0.08911323084568594;
    a[22][18] = 0.46641409889747604;
    a[22][19] = 0.450273629235458;
    a[22][20] = 0.18385224633268188;

    a[23][0] = 0.010711497314914442;
    a[23][7] = -0.07094336118221108;
    a[23][8] = 0.10021649003400916;
    a[23][9] = 0.13834539804680251;
    a[23][10] = 0.17963306335781634;
    a[23][11] = 0.09048246545576182;
    a[23][12] = -0.005460662294523339;
    a[23][13] = -0.030004579051196197;
    a[23][14] = -0.011451920269627991;
    a[23][16] = 0.010033946861093851;
    a[23][17] = -0.09506485282809046;
    a[23][18] = 0.04853358804093592;
    a[23][19] = 0.08013325919783924;
    a[23][20] = -0.1251643326835242;

    a[24][0] = 0.014101720888692213;
    a[24][7] = -0.3713379753704491;
    a[24][8] = 0.22312655481171803;
    a[24][9] = 0.12870053459181202;
    a[24][10] = 0.22246006596754947;
    a[24][11] = 0.5382853042550702;
    a[24][12] = 0.05417202616988763;
    a[24][13] = 0.1256968791308744;
    a[24][14] = 0.027844927890020542;
    a[24][16] = -0.0307740924620506;
    a[24][17] = 0.008569805293689777;
    a[24][18] = -0.15351746905870445;
    a[24][19] = -0.021799570305481963;
    a[24][20] = 0.014471288197371868;

    a[25][0] = 0.014246004117356466;
    a[25][7] = -0.3767107393295407;
    a[25][8] = 0.22523997807304214;
    a[25][9] = 0.128360307629253;
    a[25][10] = 0.22302387052616926;
    a[25][11] = 0.5463127827750747;
    a[25][12] = 0.0552619079137578;
    a[25][13] = 0.12856135087499826;
    a[25][14] = 0.028572506812964065;
    a[25][16] = -0.02398761886357109;
    a[25][17] = 0.055562244589105095;
    a[25][18] = -0.017406756507628386;
    a[25][19] = -0.03815462365996979;
    a[25][20] = 0.011118785048989178;
    a
};

/// Order-9 weights b on stages 0..15 (row `NEW` of `A`; kept for the tests that check it).
#[cfg(test)]
const B: [(usize, f64); 9] = [
    (0, 0.014611976858423152),
    (7, -0.3915211862331339),
    (8, 0.23109325002895065),
    (9, 0.12747667699928525),
    (10, 0.2246434176204158),
    (11, 0.5684352689748513),
    (12, 0.058258715572158275),
    (13, 0.13643174034822156),
    (14, 0.030570139830827976),
];

/// b − b̂: the error estimate is h·Σ E_j k_j.
const E: [(usize, f64); 10] = [
    (0, -0.005357988290444578),
    (7, -2.583020491182464),
    (8, 0.14252253154686625),
    (9, 0.013420653512688676),
    (10, -0.02867296291409493),
    (11, 2.624999655215792),
    (12, -0.2825509643291537),
    (13, 0.13643174034822156),
    (14, 0.030570139830827976),
    (15, -0.04834231373823958),
];

/// Interpolant weights: b_j(θ) = Σ_p R[j][p]·θ^(p+1), on the stages of `DENSE_STAGES`.
const DENSE_STAGES: [usize; 19] = [
    0, 7, 8, 9, 10, 11, 12, 13, 14, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25,
];
const R: [[f64; 9]; 19] = [
    [
        1.0,
        -28.330488700617398,
        257.6535452078578,
        -1152.1544557434572,
        2909.390878345409,
        -4355.005172868188,
        3834.083497036262,
        -1835.419052683407,
        368.7958613829998,
    ],
    [
        0.0,
        2.649656243770091,
        -96.30312807816006,
        869.3095462492796,
        -3395.688567551074,
        6796.933987158715,
        -7340.848417712072,
        4082.8488969923656,
        -919.2934944890586,
    ],
    [
        0.0,
        -1.5639451819287329,
        56.8423973927286,
        -513.1052300304285,
        2004.2867021103232,
        -4011.8533059139295,
        4332.895839278586,
        -2409.8793479371448,
        542.6079835318221,
    ],
    [
        0.0,
        -0.8627103334967224,
        31.355653751851733,
        -283.0413682227354,
        1105.613463426007,
        -2213.0362006784526,
        2390.1310977541207,
        -1329.3482661468738,
        299.31580712657853,
    ],
    [
        0.0,
        -1.5202953379012147,
        55.25592121120227,
        -498.7844190970741,
        1948.346888525776,
        -3899.8821364075516,
        4211.964345158858,
        -2342.619408856117,
        527.4637482204279,
    ],
    [
        0.0,
        -3.8469388441255234,
        139.81898409868404,
        -1262.1186876216004,
        4930.075848057311,
        -9868.21948606954,
        10657.908924348867,
        -5927.738759872814,
        1334.688551172191,
    ],
    [
        0.0,
        -0.39427130612001415,
        14.329994760676497,
        -129.35406659945582,
        505.28160770025175,
        -1011.3900801394333,
        1092.3250517818917,
        -607.531701930281,
        136.79172444804232,
    ],
    [
        0.0,
        -0.9233145622082102,
        33.55834582309799,
        -302.9246397549736,
        1183.2813069678675,
        -2368.4989867901113,
        2558.034559755808,
        -1422.7331755778803,
        320.3423358787482,
    ],
    [
        0.0,
        -0.20688628029300538,
        7.519388975651663,
        -67.87605708082904,
        265.136799698415,
        -530.7074807559026,
        573.176549564149,
        -318.7905688834869,
        71.77882490212657,
    ],
    [
        0.0,
        -0.44724419067440996,
        16.44684676010504,
        -154.40861059212955,
        641.8986298540249,
        -1391.9392256879823,
        1643.890568302952,
        -1004.0652972233179,
        248.6243327770223,
    ],
    [
        0.0,
        -0.1507876007899798,
        5.527328824824632,
        -51.33833743084619,
        209.60220027032804,
        -442.7692650421826,
        505.0579312588053,
        -295.63364106156195,
        69.70457078142275,
    ],
    [
        0.0,
        -0.6413652207435296,
        23.510132486246846,
        -218.36426832469724,
        891.5292818535365,
        -1883.290177206008,
        2148.2309544883997,
        -1257.4584015217124,
        296.4838434449778,
    ],
    [
        0.0,
        1.8107293134448457,
        -66.37479657295337,
        616.4952025401107,
        -2517.0030307773227,
        5316.984175781034,
        -6064.976140789574,
        3550.1095388883914,
        -837.0456783831302,
    ],
    [
        0.0,
        0.05176008760353718,
        -1.8973378625803488,
        17.622648207936294,
        -71.94907400242467,
        151.9871383765666,
        -173.36864987478606,
        101.4806461521468,
        -23.927131084462175,
    ],
    [
        0.0,
        31.321782556688,
        -355.6570858339106,
        1752.6852824895159,
        -4708.092293138363,
        7370.900776193489,
        -6716.504964764566,
        3303.940398161186,
        -678.5938956640391,
    ],
    [
        0.0,
        -2.7196073341859246,
        86.64045615858264,
        -454.1926030939031,
        1014.7492211005434,
        -1133.583456714544,
        610.4671827718666,
        -109.02334994495438,
        -12.337842943405471,
    ],
    [
        0.0,
        3.1772148014329233,
        -113.8098697715143,
        978.0935981825675,
        -3575.1293776236703,
        6764.3615198384505,
        -6987.161043852012,
        3751.9057627895713,
        -821.4378043648254,
    ],
    [
        0.0,
        0.877284308346553,
        -31.51810423988375,
        273.1229151353221,
        -993.2198643101782,
        1787.888078312664,
        -1677.394835799641,
        781.3579535062688,
        -141.11342691289855,
    ],
    [
        0.0,
        1.7194275817987157,
        -62.89867309250732,
        580.333550787398,
        -2348.110620506761,
        4921.119298612906,
        -5597.912448707917,
        3288.5977751496216,
        -782.8483098245397,
    ],
];

pub(crate) struct Vern9 {
    n: usize,
    /// Stage derivatives, stage s at [s*n, (s+1)*n).
    k: Vec<f64>,
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
    err: Vec<f64>,
    control: PiController,
    scratch: InitialStepScratch,
}

impl Vern9 {
    pub(crate) fn new(n: usize) -> Self {
        Vern9 {
            n,
            k: vec![0.0; STAGES * n],
            x_stage: vec![0.0; n],
            x_new: vec![0.0; n],
            err: vec![0.0; n],
            control: PiController::new(1.0 / 9.0 - 0.2 * 0.04, 0.04, 0.333, 6.0),
            scratch: InitialStepScratch::new(n),
        }
    }

    /// x_stage = x + h * sum_j a[s][j] k_j. The stage index is a const parameter so that the
    /// loop over `A[S]` unrolls with its coefficients as constants and its zeros fold away (as
    /// in DOP853).
    fn combine<const S: usize>(&mut self, x: &[f64], h: f64) {
        let n = self.n;
        for (i, (xs, &xi)) in self.x_stage.iter_mut().zip(x).enumerate() {
            let mut acc = xi;
            for j in 0..S {
                let a = A[S][j];
                if a != 0.0 {
                    acc += (h * a) * self.k[j * n + i];
                }
            }
            *xs = acc;
        }
    }

    /// k_s = f(t + c_s h, x + h * sum_j a[s][j] k_j).
    fn stage<const S: usize, Sys: OdeSystem>(
        &mut self,
        sys: &mut Sys,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
    ) {
        self.combine::<S>(x, h);
        let n = self.n;
        sys.rhs(
            w.at(t + C[S] * h),
            &self.x_stage,
            &mut self.k[S * n..(S + 1) * n],
        );
    }
}

impl Stepper for Vern9 {
    const STRETCH: f64 = 1.01;

    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) -> Result<(), SolveError> {
        self.control.reset();
        start_derivative(sys, w, t, x, &mut self.k[..self.n], stats)
    }

    fn first_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        tol: &Tolerances,
        h_max: f64,
        stats: &mut SolverStats,
    ) -> f64 {
        let f0 = &self.k[..self.n];
        initial_step(sys, w, t, x, f0, 9, tol, h_max, &mut self.scratch, stats)
    }

    fn attempt<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        tol: &Tolerances,
        stats: &mut SolverStats,
    ) -> Result<Attempt, SolveError> {
        let n = self.n;
        self.stage::<1, _>(sys, w, t, x, h);
        self.stage::<2, _>(sys, w, t, x, h);
        self.stage::<3, _>(sys, w, t, x, h);
        self.stage::<4, _>(sys, w, t, x, h);
        self.stage::<5, _>(sys, w, t, x, h);
        self.stage::<6, _>(sys, w, t, x, h);
        self.stage::<7, _>(sys, w, t, x, h);
        self.stage::<8, _>(sys, w, t, x, h);
        self.stage::<9, _>(sys, w, t, x, h);
        self.stage::<10, _>(sys, w, t, x, h);
        self.stage::<11, _>(sys, w, t, x, h);
        self.stage::<12, _>(sys, w, t, x, h);
        self.stage::<13, _>(sys, w, t, x, h);
        self.stage::<14, _>(sys, w, t, x, h);
        self.stage::<15, _>(sys, w, t, x, h);
        stats.rhs_evals += 15;
        // The new point: row NEW of A is b.
        self.combine::<NEW>(x, h);
        std::mem::swap(&mut self.x_new, &mut self.x_stage);

        for (i, e) in self.err.iter_mut().enumerate() {
            let mut acc = 0.0;
            for &(j, ej) in &E {
                acc += ej * self.k[j * n + i];
            }
            *e = h * acc;
        }
        let err = error_norm(&self.err, x, &self.x_new, tol);
        let attempt = self.control.decide(err, h);
        if attempt.accepted && self.x_new.iter().all(|v| v.is_finite()) {
            // The derivative at the new point: the interpolant's stage 16 and the next step's
            // stage 0.
            sys.rhs(
                w.at(t + h),
                &self.x_new,
                &mut self.k[NEW * n..(NEW + 1) * n],
            );
            stats.rhs_evals += 1;
        }
        Ok(attempt)
    }

    fn x_new(&self) -> &[f64] {
        &self.x_new
    }

    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>) {
        let n = self.n;
        (&mut self.x_new, Some(&mut self.k[NEW * n..(NEW + 1) * n]))
    }

    fn prepare_dense<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        stats: &mut SolverStats,
    ) {
        self.stage::<17, _>(sys, w, t, x, h);
        self.stage::<18, _>(sys, w, t, x, h);
        self.stage::<19, _>(sys, w, t, x, h);
        self.stage::<20, _>(sys, w, t, x, h);
        self.stage::<21, _>(sys, w, t, x, h);
        self.stage::<22, _>(sys, w, t, x, h);
        self.stage::<23, _>(sys, w, t, x, h);
        self.stage::<24, _>(sys, w, t, x, h);
        self.stage::<25, _>(sys, w, t, x, h);
        stats.rhs_evals += 9;
    }

    /// Ends on the step's own new point: after a projection moved it (`keep_jacobi_integral`)
    /// the samples inside the step keep the unprojected arc, off by the projection's correction.
    fn dense(&self, x_old: &[f64], theta: f64, h: f64, out: &mut [f64]) {
        let n = self.n;
        // b_j(θ) by Horner, once per sample.
        let mut b = [0.0; DENSE_STAGES.len()];
        for (bj, r) in b.iter_mut().zip(&R) {
            let mut p = 0.0;
            for &c in r.iter().rev() {
                p = p * theta + c;
            }
            *bj = p * theta;
        }
        for (i, o) in out.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (&j, &bj) in DENSE_STAGES.iter().zip(&b) {
                acc += bj * self.k[j * n + i];
            }
            *o = x_old[i] + h * acc;
        }
    }

    fn accept(&mut self) {
        let n = self.n;
        self.k.copy_within(NEW * n..(NEW + 1) * n, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row's weights sum to its abscissa (the stages are consistent).
    #[test]
    fn rows_sum_to_abscissae() {
        for s in 1..STAGES {
            let sum: f64 = A[s].iter().sum();
            assert!((sum - C[s]).abs() < 1e-13, "row {s}: {sum} vs c = {}", C[s]);
        }
        let b: f64 = B.iter().map(|&(_, v)| v).sum();
        assert!((b - 1.0).abs() < 1e-14);
        let e: f64 = E.iter().map(|&(_, v)| v).sum();
        assert!(e.abs() < 1e-14, "b − b̂ must sum to 0, got {e}");
    }

    /// Row NEW is b, and the interpolant at θ = 1 is b (the dense output ends on x_new).
    #[test]
    fn interpolant_ends_on_the_step() {
        for &(j, bj) in &B {
            assert_eq!(A[NEW][j], bj, "row {NEW} differs from b at stage {j}");
        }
        for (&j, r) in DENSE_STAGES.iter().zip(&R) {
            let at_one: f64 = r.iter().sum();
            let want = B.iter().find(|&&(i, _)| i == j).map_or(0.0, |&(_, v)| v);
            assert!(
                (at_one - want).abs() < 1e-9,
                "stage {j}: b_j(1) = {at_one}, b = {want}"
            );
        }
    }

    /// Rooted trees up to order `max` as lists of children (indices of smaller trees), with
    /// their orders and densities γ: every tree once (children in non-increasing index order).
    fn trees(max: usize) -> Vec<(Vec<usize>, usize, f64)> {
        let mut all: Vec<(Vec<usize>, usize, f64)> = vec![(vec![], 1, 1.0)];
        for n in 2..=max {
            // Multisets of earlier trees whose orders sum to n - 1.
            fn extend(
                all: &[(Vec<usize>, usize, f64)],
                left: usize,
                below: usize,
                kids: &mut Vec<usize>,
                out: &mut Vec<Vec<usize>>,
            ) {
                if left == 0 {
                    out.push(kids.clone());
                    return;
                }
                for i in (0..below).rev() {
                    if all[i].1 <= left {
                        kids.push(i);
                        extend(all, left - all[i].1, i + 1, kids, out);
                        kids.pop();
                    }
                }
            }
            let mut new = Vec::new();
            extend(&all, n - 1, all.len(), &mut Vec::new(), &mut new);
            for kids in new {
                let gamma = n as f64 * kids.iter().map(|&k| all[k].2).product::<f64>();
                all.push((kids, n, gamma));
            }
        }
        all
    }

    /// g(t)_i = Π_children (Σ_j a_ij g(child)_j) for every tree, on the first `s` stages.
    fn stage_weights(trees: &[(Vec<usize>, usize, f64)], s: usize) -> Vec<Vec<f64>> {
        let mut g: Vec<Vec<f64>> = Vec::with_capacity(trees.len());
        for (kids, _, _) in trees {
            let mut v = vec![1.0; s];
            for &k in kids {
                for (i, vi) in v.iter_mut().enumerate() {
                    *vi *= (0..s).map(|j| A[i][j] * g[k][j]).sum::<f64>();
                }
            }
            g.push(v);
        }
        g
    }

    /// Every order condition Σ b_i g(t)_i = 1/γ(t) of the 486 rooted trees up to order 9 holds
    /// for b, of the 200 up to order 8 for the embedded b̂ = b − E, and θ^|t|/γ(t) for the
    /// interpolant's b(θ) up to order 9 on all 26 stages: a proof that the tables are the pair
    /// they claim to be, which a mistyped digit breaks.
    #[test]
    fn order_conditions_hold() {
        let t = trees(9);
        assert_eq!(t.len(), 486);
        let g = stage_weights(&t, STAGES);
        let phi = |w: &dyn Fn(usize) -> f64, tree: usize| -> f64 {
            (0..STAGES).map(|i| w(i) * g[tree][i]).sum()
        };
        let b = |i: usize| B.iter().find(|&&(j, _)| j == i).map_or(0.0, |&(_, v)| v);
        let e = |i: usize| E.iter().find(|&&(j, _)| j == i).map_or(0.0, |&(_, v)| v);
        let mut worst: f64 = 0.0;
        for (k, (_, order, gamma)) in t.iter().enumerate() {
            let d = (phi(&b, k) * gamma - 1.0).abs();
            worst = worst.max(d);
            assert!(d < 1e-10, "b: tree {k} of order {order}: Φγ − 1 = {d:e}");
            if *order <= 8 {
                let d = (phi(&|i| b(i) - e(i), k) * gamma - 1.0).abs();
                assert!(d < 1e-10, "b̂: tree {k} of order {order}: Φγ − 1 = {d:e}");
            }
            for theta in [0.3, 0.7] {
                let mut bt = [0.0; STAGES];
                for (&j, r) in DENSE_STAGES.iter().zip(&R) {
                    bt[j] = r.iter().rev().fold(0.0, |p, &c| p * theta + c) * theta;
                }
                let want = theta.powi(*order as i32) / gamma;
                let d = ((phi(&|i| bt[i], k) - want) / want).abs();
                assert!(d < 1e-9, "b(θ = {theta}): tree {k} of order {order}: {d:e}");
            }
        }
        // The embedded pair is of order 8, not 9: some order-9 condition fails for b̂.
        let worst_hat = (0..t.len())
            .filter(|&k| t[k].1 == 9)
            .map(|k| (phi(&|i| b(i) - e(i), k) * t[k].2 - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst_hat > 1e-6, "b̂ satisfies order 9 too ({worst_hat:e})");
        eprintln!("worst order-9 residual of b: {worst:.1e}; of b̂: {worst_hat:.1e}");
    }
}
