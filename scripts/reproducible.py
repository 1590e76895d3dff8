"""The surveys' records bit for bit alike on every x86-64 machine with AVX2 and FMA.

numpy's SIMD loops (its transcendental functions among them), OpenBLAS' kernels (which scipy's
LSODA calls for its linear algebra) and numba's machine code are chosen at run time for the CPU
at hand: on a machine with AVX-512 they round differently from one with AVX2 alone, the adaptive
solver then takes other steps, and the same seed gives another record. A record that sits near a
decision (seed 3 of survey_lines.py: an extra friction beside its play, 6.5 in the information
criterion ahead of the play alone where 6 names a finding) then gets another answer on another
machine, and a test that guards it fails there. Each is held here at the x86-64-v3 level
(Haswell: AVX2, FMA), which every machine of this project's kinds has. Imported before numpy,
scipy and numba, as the first import of every survey script; a value set in the environment
already is kept.
"""

import os

for key, value in {
    # numpy's dispatch: no X86_V4 (AVX-512) loops, nor the later AVX-512 groups
    "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
    # OpenBLAS (numpy's and scipy's copies): the Haswell kernels
    "OPENBLAS_CORETYPE": "Haswell",
    # numba: code for a Haswell CPU with that CPU's own features (empty: none added from the
    # host's, which would bring AVX-512 back)
    "NUMBA_CPU_NAME": "haswell",
    "NUMBA_CPU_FEATURES": "",
}.items():
    os.environ.setdefault(key, value)
