"""Reference numbers for tests/linalg_stiff.rs: SciPy's eigenvalues and matrix exponentials of
the linearised Anschutz 1906 at 50 N (the matrix STIFF_A of that test, pasted below).

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install numpy scipy
    /tmp/venv/bin/python crates/gyro-model/tests/data/linalg_scipy.py

prints the Rust constants SCIPY_EIGENVALUES and SCIPY_EXPM that the test holds
`linalg::eigenvalues` and `linalg::expm` to (the numbers in the test were made with the
versions it prints).
"""

import numpy as np
import scipy
import scipy.linalg

# STIFF_A of tests/linalg_stiff.rs (row-major), as `CompiledModel::linear_matrix()` gave it.
A = np.array(
    [
        [0e0, 0e0, 0e0, 0e0, 1e0, 0e0, 0e0, 0e0],
        [0e0, 0e0, 0e0, 0e0, 0e0, 1e0, 0e0, 0e0],
        [0e0, 0e0, 0e0, 0e0, 0e0, 0e0, 1e0, 0e0],
        [0e0, 0e0, 0e0, 0e0, 0e0, 0e0, 0e0, 1e0],
        [-2.5842630091144483e-2, 2.8257512518027134e-1, 2.5126462898690844e-3, -4.51771118757802e-1, -3.610467922302224e-1, 5.51335130907677e2, 3.341900504416482e-4, 7.500027147705088e-6],
        [-1.6742379892797196e-5, -2.9918780087626157e1, 2.895424205800288e-5, 1.5687155987906928e-1, -5.723677726605322e2, 3.531808710492294e-1, -3.664858540023779e-5, 1.2019724427470345e-2],
        [2.2376026757491177e-6, 2.671319062769664e-6, -3.938271506920563e1, 3.897219827762489e-5, 5.503110276980388e-4, -4.768188762940126e-2, -5.237332492724041e0, 7.475430892930405e-8],
        [5.022713967320248e-5, -3.0250965973444363e2, -8.686272617351029e-5, -3.927366146832003e2, 1.7171033226688778e3, -1.0595426130368044e0, -2.1963321007980672e-4, -2.0036059173282407e1],
    ]
)
STEPS_S = [1e-3, 1.0, 100.0, 3600.0]

print(f"// numpy {np.__version__}, scipy {scipy.__version__}")
ev = scipy.linalg.eigvals(A)
ev = sorted(ev, key=lambda z: (abs(z), z.imag))
print("const SCIPY_EIGENVALUES: [(f64, f64); N_STIFF] = [")
for z in ev:
    print(f"    ({float(z.real)!r}, {float(z.imag)!r}),")
print("];")
print("const SCIPY_EXPM: [(f64, [f64; N_STIFF * N_STIFF]); %d] = [" % len(STEPS_S))
for h in STEPS_S:
    e = scipy.linalg.expm(A * h)
    print(f"    ({h!r}, [")
    for row in e:
        print("        " + ", ".join(repr(float(x)) for x in row) + ",")
    print("    ]),")
print("];")
