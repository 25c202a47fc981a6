"""Writes ``src/qmc/joe_kuo.bin``, the Sobol' direction numbers the Rust core
reads, from the table scipy ships (Joe and Kuo's ``new-joe-kuo-6.21201``:
S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better
two-dimensional projections", SIAM J. Sci. Comput. 30, 2635-2654, 2008).

Layout, little-endian, for dimensions 1 .. 21200 (dimension 0 is the van der
Corput sequence and needs no numbers): the primitive polynomial ``p`` as 3
bytes (its bits, leading and constant terms included, so its degree is
``s = floor(log2 p)``), then the ``s`` initial numbers ``m_1 .. m_s``
(``m_k`` odd and below ``2^k``), each in 1 byte if ``k <= 8``, 2 if
``k <= 16``, else 3.

Run from the repository root: ``python tools/pack_sobol_directions.py``.
"""

import pathlib

import numpy as np
import scipy.stats

table = np.load(pathlib.Path(scipy.stats.__file__).parent / "_sobol_direction_numbers.npz")
poly, vinit = table["poly"], table["vinit"]
out = bytearray()
for d in range(1, len(poly)):
    p = int(poly[d])
    s = p.bit_length() - 1
    out += p.to_bytes(3, "little")
    for k in range(1, s + 1):
        m = int(vinit[d, k - 1])
        assert m % 2 == 1 and m < 2**k, (d, k, m)
        out += m.to_bytes(1 if k <= 8 else 2 if k <= 16 else 3, "little")
path = pathlib.Path("src/qmc/joe_kuo.bin")
path.write_bytes(bytes(out))
print(f"{path}: {len(poly)} dimensions, {len(out)} bytes")
