"""The principal axis of a group's ``2 x 2`` scatter, as ``np.linalg.eigh`` computes it.

APCS fits a flat wall to a closed ERP group along the principal axis of the group's scatter
matrix and tests the variance across it (Yamamoto et al., sec. 4.2.2-4.2.3). ``np.linalg.eigh``
costs about 17 us per call, nearly all of it numpy's and LAPACK's set-up around a ``2 x 2``
problem. :func:`principal_axis` takes LAPACK's own path for that size, step by step in one
compiled loop, so it gives ``eigh``'s bits at a small part of the cost.

For ``n = 2`` LAPACK's ``dsyevd`` (``JOBZ = 'V'``, ``UPLO = 'L'``, what numpy calls) does no
Householder step (``dsytrd`` leaves the matrix as it is: ``dlarfg`` of one element gives
``tau = 0``) and hands the diagonal ``d`` and the subdiagonal ``e`` to ``dsteqr`` (via
``dstedc``, the size being under its divide-and-conquer threshold). ``dsteqr``:

1. splits off ``e`` when ``|e| <= sqrt|d1| sqrt|d2| eps``;
2. otherwise takes QL iteration when ``|d2| >= |d1|`` and QR iteration otherwise, whose test
   for a negligible ``e`` is ``e^2 <= eps^2 |d_l| |d_m| + safmin`` in each one's order;
3. solves a remaining ``2 x 2`` block with ``dlaev2`` and rotates the identity with ``dlasr``;
4. sorts the eigenvalues ascending by selection, swapping eigenvector columns.

``eps = 2^-53`` and ``safmin = 2^-1022`` are ``dlamch('E')`` and ``dlamch('S')``. Both routines
rescale a matrix whose largest entry lies outside about ``[1e-122, 1e146]``; there
:func:`principal_axis` does not answer and its caller calls ``eigh``. The tests compare the
bits with ``np.linalg.eigh`` over random, degenerate and near-diagonal matrices.
"""

from __future__ import annotations

import math

from numba import types

from sonar_gym.compiled import TABLE, compiled
from sonar_gym.pose import FloatArray

_EPS = 2.0**-53
"""LAPACK's ``dlamch('E')``: the relative machine precision (unit round-off)."""
_SAFMIN = 2.0**-1022
"""LAPACK's ``dlamch('S')``: the smallest normal number."""
_SMALLEST_UNSCALED = 1e-120
"""Inside ``dsteqr``'s lower scaling bound ``sqrt(safmin) / eps^2 = 2^-405`` (about 1.5e-122)."""
_LARGEST_UNSCALED = 1e145
"""Inside ``dsyevd``'s upper scaling bound ``sqrt(eps / safmin) = 2^485`` (about 1e146)."""


@compiled(  # type: ignore[misc]
    types.UniTuple(types.float64, 4),
    types.float64,
    types.float64,
    types.float64,
    inline=True,
)
def _laev2(a: float, b: float, c: float) -> tuple[float, float, float, float]:
    """LAPACK's ``dlaev2``: ``(rt1, rt2, cs1, sn1)`` of ``[[a, b], [b, c]]``, ``rt1`` the
    eigenvalue of larger absolute value and ``(cs1, sn1)`` its unit eigenvector."""
    sm = a + c
    df = a - c
    adf = abs(df)
    tb = b + b
    ab = abs(tb)
    if abs(a) > abs(c):
        acmx, acmn = a, c
    else:
        acmx, acmn = c, a
    if adf > ab:
        ratio = ab / adf
        rt = adf * math.sqrt(1.0 + ratio * ratio)
    elif adf < ab:
        ratio = adf / ab
        rt = ab * math.sqrt(1.0 + ratio * ratio)
    else:
        rt = ab * math.sqrt(2.0)
    if sm < 0.0:
        rt1 = 0.5 * (sm - rt)
        sgn1 = -1
        rt2 = (acmx / rt1) * acmn - (b / rt1) * b
    elif sm > 0.0:
        rt1 = 0.5 * (sm + rt)
        sgn1 = 1
        rt2 = (acmx / rt1) * acmn - (b / rt1) * b
    else:
        rt1 = 0.5 * rt
        rt2 = -0.5 * rt
        sgn1 = 1
    if df >= 0.0:
        cs = df + rt
        sgn2 = 1
    else:
        cs = df - rt
        sgn2 = -1
    if abs(cs) > ab:
        ct = -tb / cs
        sn1 = 1.0 / math.sqrt(1.0 + ct * ct)
        cs1 = ct * sn1
    elif ab == 0.0:
        cs1 = 1.0
        sn1 = 0.0
    else:
        tn = -cs / tb
        cs1 = 1.0 / math.sqrt(1.0 + tn * tn)
        sn1 = tn * cs1
    if sgn1 == sgn2:
        cs1, sn1 = -sn1, cs1
    return rt1, rt2, cs1, sn1


@compiled(  # type: ignore[misc]
    types.Tuple((types.boolean, types.float64, types.float64, types.float64)),
    TABLE,
    types.float64,
)
def principal_axis(scatter: FloatArray, count: float) -> tuple[bool, float, float, float]:
    """``(answered, smallest, along_x, along_y)`` of ``np.linalg.eigh(scatter / count)``.

    Args:
        scatter: ``(2, 2)`` the group's summed outer products about its centroid (m^2); only
            its lower triangle is read, as ``eigh`` reads it.
        count: the number of ERPs it sums.

    Returns:
        Whether the matrix lies in LAPACK's unscaled range (see the module); if so, the
        smaller eigenvalue (m^2, the variance across the axis) and ``eigh``'s eigenvector of
        the larger one (the axis), otherwise ``(False, nan, nan, nan)``.
    """
    d1 = scatter[0, 0] / count
    e = scatter[1, 0] / count
    d2 = scatter[1, 1] / count
    largest = max(abs(d1), abs(e), abs(d2))
    unscaled = largest == 0.0 or _SMALLEST_UNSCALED <= largest <= _LARGEST_UNSCALED
    if not (unscaled and math.isfinite(d1) and math.isfinite(e) and math.isfinite(d2)):
        return False, math.nan, math.nan, math.nan
    # the identity, which dlasr rotates; z_ij is row i, column j
    z11, z21, z12, z22 = 1.0, 0.0, 0.0, 1.0
    tst = abs(e)
    split = tst == 0.0 or tst <= (math.sqrt(abs(d1)) * math.sqrt(abs(d2))) * _EPS
    if not split:
        eps2 = _EPS * _EPS
        square = tst * tst
        if abs(d2) < abs(d1):  # QR iteration looks from the bottom
            negligible = square <= (eps2 * abs(d2)) * abs(d1) + _SAFMIN
        else:  # QL iteration looks from the top
            negligible = square <= (eps2 * abs(d1)) * abs(d2) + _SAFMIN
        if not negligible:
            rt1, rt2, c, s = _laev2(d1, e, d2)
            # dlasr('R', 'V', 'B' or 'F') over the two rows of z: the same rotation either way
            temp = z12
            z12 = c * temp - s * z11
            z11 = s * temp + c * z11
            temp = z22
            z22 = c * temp - s * z21
            z21 = s * temp + c * z21
            d1, d2 = rt1, rt2
    if d2 < d1:  # the selection sort's one swap, of the values and of the eigenvector columns
        return True, d2, z11, z21
    return True, d1, z12, z22
