"""The QZ path's own call of LAPACK ggev (mbseig.eigen.dense_paths._ggev) gives what
``scipy.linalg.eig(A, B, left, right=True, homogeneous_eigvals=True)`` gives, byte for byte
(the same driver, workspace and vector formation; scipy's per-column norm replaced by the BLAS
nrm2 it calls): eigenvalues, right and left vectors, signed zeros included, for real pencils
with conjugate pairs, a real spectrum and complex pencils.  One kernel, the same calls: equal
under any BLAS or under none."""

import numpy as np
import pytest
import scipy.linalg as sla

from mbseig.eigen.dense_paths import _ggev


def _pencils():
    rng = np.random.default_rng(3)
    yield rng.standard_normal((84, 84)), rng.standard_normal((84, 84))  # pairs and reals
    yield np.diag([3.0, -1.0, 2.0, 0.0]), np.eye(4)  # a real spectrum, one zero
    yield (rng.standard_normal((12, 12)) + 1j * rng.standard_normal((12, 12)),
           rng.standard_normal((12, 12)).astype(complex))


@pytest.mark.parametrize("left", [False, True])
def test_ggev_is_scipys_eig(left):
    for A, B in _pencils():
        ref = sla.eig(A, B, left=left, right=True, homogeneous_eigvals=True,
                      check_finite=False)
        w, W, Z = _ggev(A.copy(), B.copy(), left)
        assert w.tobytes() == ref[0].tobytes()
        assert Z.dtype == ref[-1].dtype and Z.tobytes() == ref[-1].tobytes()
        if left:
            assert W.tobytes() == ref[1].tobytes()
        else:
            assert W is None
