"""Forward dynamics of the benchmark chains in 40-digit arithmetic.

Featherstone's articulated-body algorithm (RBDA, table 7.1) in `mpmath`,
for the serial revolute chains of ``models.py`` (``arm7``, the planar and
spatial chains): the arbiter of the peers' acceleration check. Two double
precision results that differ tell nothing about which is right; on the
200-link chain, whose mass matrix has a condition number of about 1e9,
MuJoCo's `mj_forward` (composite rigid bodies and an LDLᵀ of `M`) is off
by up to κ(M)·ε while recursive algorithms are not (BENCHMARKS.md,
"Peers": the 200-link chain's acceleration check). Spatial vectors are
(angular; linear), motion transforms parent → child; gravity enters as
the base's upward acceleration.
"""

import mpmath as mp

import models

DIGITS = 40


def _rot(axis, q):
    """Rotation matrix of the child frame in the parent's: `q` about `axis`."""
    c, s = mp.cos(q), mp.sin(q)
    x, y, z = (mp.mpf(a) for a in axis)
    k = 1 - c
    return mp.matrix(
        [
            [c + x * x * k, x * y * k - z * s, x * z * k + y * s],
            [y * x * k + z * s, c + y * y * k, y * z * k - x * s],
            [z * x * k - y * s, z * y * k + x * s, c + z * z * k],
        ]
    )


def _skew(r):
    return mp.matrix([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def _blocks(a, b, c, d):
    m = mp.matrix(6, 6)
    for i in range(3):
        for j in range(3):
            m[i, j], m[i, j + 3], m[i + 3, j], m[i + 3, j + 3] = a[i, j], b[i, j], c[i, j], d[i, j]
    return m


def _cross_motion(v):
    w, u = _skew(v[0:3]), _skew(v[3:6])
    return _blocks(w, mp.zeros(3, 3), u, w)


def forward_dynamics(links, q, u, tau):
    """`u̇` of the chain `links` (``models.Link``) at `q`, `u`, `tau` (floats,
    read exactly), as floats rounded from 40 digits."""
    with mp.workdps(DIGITS):
        q, u, tau = ([mp.mpf(x) for x in v] for v in (q, u, tau))
        n = len(links)
        xup, axes, bias, art, pa = [], [], [], [], []
        v_parent = mp.zeros(6, 1)
        for i, ln in enumerate(links):
            e = _rot(ln.axis, q[i]).T
            xup.append(_blocks(e, mp.zeros(3, 3), -e * _skew(mp.matrix(ln.joint_pos)), e))
            s = mp.matrix([ln.axis[0], ln.axis[1], ln.axis[2], 0, 0, 0])
            axes.append(s)
            cx = _skew(mp.matrix(ln.com))
            inertia = _blocks(
                mp.diag([mp.mpf(x) for x in ln.inertia]) + ln.mass * cx * cx.T,
                ln.mass * cx,
                ln.mass * cx.T,
                ln.mass * mp.eye(3),
            )
            v = xup[i] * v_parent + s * u[i]
            bias.append(_cross_motion(v) * (s * u[i]))
            art.append(inertia)
            pa.append(-_cross_motion(v).T * (inertia * v))
            v_parent = v
        uu, d, w = [None] * n, [None] * n, [None] * n
        for i in reversed(range(n)):
            uu[i] = art[i] * axes[i]
            d[i] = (axes[i].T * uu[i])[0]
            w[i] = tau[i] - (axes[i].T * pa[i])[0]
            if i:
                ia = art[i] - uu[i] * uu[i].T / d[i]
                p = pa[i] + ia * bias[i] + uu[i] * (w[i] / d[i])
                art[i - 1] += xup[i].T * ia * xup[i]
                pa[i - 1] += xup[i].T * p
        a = mp.matrix([0, 0, 0, 0, 0, models.GRAVITY])
        out = []
        for i in range(n):
            a = xup[i] * a + bias[i]
            qdd = (w[i] - (uu[i].T * a)[0]) / d[i]
            a = a + axes[i] * qdd
            out.append(float(qdd))
        return out
