"""Linear time-invariant systems with numpy alone: what the servo loop needs.

The loop (:mod:`.loop`) is a continuous-time state space; this module gives it

* :class:`StateSpace` (``A, B, C, D`` as arrays) and :func:`pade_delay`, the loop delay as a
  Padé approximation (the same transfer function as python-control's ``pade``);
* :func:`forced_response`: the response to inputs sampled on a uniform time grid, exact for inputs
  linear between the samples (first-order hold: the state transition of the system augmented with
  the inputs and their slope over one step, the method of python-control's ``forced_response`` and
  scipy's ``lsim``), several sets of inputs at once;
* :func:`periodic_steady_state`: the periodic response to periodic inputs (the state at the cycle
  start solves ``x0 = Phi x0 + x_forced(T)``);
* :func:`expm` (balanced, then a Padé approximation with scaling and squaring) and :func:`stability_margins` of a
  loop transfer function ``num(s)/den(s)`` (its crossings found as polynomial roots, the method of
  python-control's ``stability_margins``).

python-control is not imported: importing it (scipy.signal, matplotlib) took longer than a
design's whole servo computation. ``tests/servo/test_servo_lti.py`` checks these functions against
python-control where it is installed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class StateSpace:
    """``x' = A x + B u``, ``y = C x + D u`` (continuous time)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray

    @property
    def nstates(self) -> int:
        return self.A.shape[0]

    @property
    def ninputs(self) -> int:
        return self.B.shape[1]

    @property
    def noutputs(self) -> int:
        return self.C.shape[0]


def pade(delay: float, order: int) -> tuple[list[float], list[float]]:
    """Numerator and denominator (highest power of ``s`` first, ``den[0] = 1``) of the Padé
    approximation of ``exp(-delay s)`` of the given order (numerator and denominator of that degree)."""
    if not delay >= 0 or order < 0:
        raise ValueError(f"a Padé delay needs delay >= 0 and order >= 0, got {delay!r}, {order!r}")
    if delay == 0:
        return [1.0], [1.0]
    num = [0.0] * (order + 1)
    den = [0.0] * (order + 1)
    num[-1] = den[-1] = 1.0
    cn = cd = 1.0
    for k in range(1, order + 1):  # Golub and van Loan, Matrix Computations, Alg. 11.3.1
        cn *= -delay * (order - k + 1) / (2 * order - k + 1) / k
        cd *= delay * (order - k + 1) / (2 * order - k + 1) / k
        num[order - k] = cn
        den[order - k] = cd
    return [c / den[0] for c in num], [c / den[0] for c in den]


def pade_delay(delay: float, order: int) -> StateSpace:
    """The Padé delay as a state space (one input, one output; a feed-through of ``(-1)^order``).

    Realised in the scaled time ``s * delay``: the companion form of the polynomials in ``s * delay``
    (coefficients of order one to a few hundred) with every state rate divided by ``delay``, so the
    matrix holds numbers near ``1/delay`` rather than ``1/delay^order``."""
    if delay == 0 or order == 0:
        return StateSpace(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.ones((1, 1)))
    num, den = (np.asarray(p) for p in pade(1.0, order))  # in the scaled variable z = s * delay; den[0] = 1
    d = num[0]
    rest = num[1:] - d * den[1:]  # the strictly proper part, highest power first
    a = np.zeros((order, order))  # controller companion form
    a[0, :] = -den[1:]
    a[1:, :-1] = np.eye(order - 1)
    b = np.zeros((order, 1))
    b[0, 0] = 1.0
    c = rest.reshape(1, -1)
    return StateSpace(a / delay, b / delay, c, np.array([[d]]))


# --------------------------------------------------------------------------- matrix exponential

#: Padé coefficients b_k of degree m for the matrix exponential (Higham 2005, "The scaling and
#: squaring method for the matrix exponential revisited"), and the largest 1-norm each serves.
_PADE_COEFFICIENTS = {
    3: (120.0, 60.0, 12.0, 1.0),
    5: (30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0),
    7: (17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0),
    9: (17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0, 2162160.0, 110880.0, 3960.0,
        90.0, 1.0),
    13: (64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0, 129060195264000.0,
         10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0,
         1.0),
}
_THETA = {3: 1.495585217958292e-2, 5: 2.539398330063230e-1, 7: 9.504178996162932e-1, 9: 2.097847961257068e0,
          13: 5.371920351148152e0}


def balance(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(d^-1 a d, d)`` with ``d`` a diagonal of powers of two (exact scalings) that makes the rows and
    columns of ``a`` of like norm (the balancing of LAPACK's gebal, Parlett and Reinsch 1969)."""
    a = np.array(a, dtype=float)
    n = a.shape[0]
    d = np.ones(n)
    for _ in range(100):
        converged = True
        for i in range(n):
            c = float(np.sum(np.abs(a[:, i])) - abs(a[i, i]))
            r = float(np.sum(np.abs(a[i, :])) - abs(a[i, i]))
            if c == 0.0 or r == 0.0:
                continue
            total, f = c + r, 1.0
            while c < r / 2:
                f, c = f * 2.0, c * 4.0
            while c >= r * 2:
                f, c = f / 2.0, c / 4.0
            if (c + r) / f < 0.95 * total:
                converged = False
                d[i] *= f
                a[:, i] *= f
                a[i, :] /= f
        if converged:
            break
    return a, d


def expm(a: np.ndarray) -> np.ndarray:
    """``exp(a)`` of a square matrix: balanced (:func:`balance`: a system's states in unlike units make
    a large norm that scaling and squaring would pay for in accuracy), then the diagonal Padé
    approximation of the smallest degree whose error bound is below double precision for the
    1-norm, with scaling and squaring above degree 13 (Higham 2005)."""
    a = np.asarray(a, dtype=float)
    if a.shape[0] == 0:
        return np.eye(0)
    balanced, d = balance(a)
    if np.linalg.norm(balanced, 1) < np.linalg.norm(a, 1):
        return d[:, None] * _expm_pade(balanced) / d[None, :]
    return _expm_pade(a)


def _expm_pade(a: np.ndarray) -> np.ndarray:
    n = a.shape[0]
    ident = np.eye(n)
    norm = float(np.linalg.norm(a, 1))
    for m in (3, 5, 7, 9):
        if norm <= _THETA[m]:
            b = _PADE_COEFFICIENTS[m]
            a2 = a @ a
            powers = [ident, a2]
            while len(powers) < (m + 1) // 2:
                powers.append(powers[-1] @ a2)
            u = a @ sum(b[2 * k + 1] * p for k, p in enumerate(powers))
            v = sum(b[2 * k] * p for k, p in enumerate(powers))
            return np.linalg.solve(v - u, v + u)
    squarings = max(0, int(np.ceil(np.log2(norm / _THETA[13])))) if norm > 0 else 0
    a = a / 2.0**squarings
    b = _PADE_COEFFICIENTS[13]
    a2 = a @ a
    a4 = a2 @ a2
    a6 = a2 @ a4
    u = a @ (a6 @ (b[13] * a6 + b[11] * a4 + b[9] * a2) + b[7] * a6 + b[5] * a4 + b[3] * a2 + b[1] * ident)
    v = a6 @ (b[12] * a6 + b[10] * a4 + b[8] * a2) + b[6] * a6 + b[4] * a4 + b[2] * a2 + b[0] * ident
    r = np.linalg.solve(v - u, v + u)
    for _ in range(squarings):
        r = r @ r
    return r


# --------------------------------------------------------------------------- time responses


def _step(t: np.ndarray) -> float:
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or len(t) < 2:
        raise ValueError("the time grid needs at least two points")
    dt = (t[-1] - t[0]) / (len(t) - 1)
    if not np.allclose(np.diff(t), dt):
        raise ValueError("the time grid must be uniform")
    return dt


def hold_matrices(sys: StateSpace, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Ad, B0, B1)`` with ``x(t + dt) = Ad x(t) + B0 u(t) + B1 u(t + dt)`` for inputs linear over the
    step: the exponential of ``[[A dt, B dt, 0], [0, 0, I], [0, 0, 0]]``."""
    ns, ni = sys.nstates, sys.ninputs
    m = np.zeros((ns + 2 * ni, ns + 2 * ni))
    m[:ns, :ns] = sys.A * dt
    m[:ns, ns:ns + ni] = sys.B * dt
    m[ns:ns + ni, ns + ni:] = np.eye(ni)
    e = expm(m)
    b1 = e[:ns, ns + ni:]
    return e[:ns, :ns], e[:ns, ns:ns + ni] - b1, b1


def linear_recurrence(ad: np.ndarray, f: np.ndarray, x0: np.ndarray, states: bool = True) -> np.ndarray:
    """``x[i] = ad x[i-1] + f[i-1]`` from ``x[0] = x0`` over ``len(f)`` steps: every state ``(len(f) + 1, n, sets)``,
    or with ``states`` false the last one ``(n, sets)``.

    In blocks of ``K`` steps (``K`` about the square root of the steps): the forced response within every
    block from rest, all blocks at once (``K`` matrix products), then the state carried from block to block
    by ``ad^K``, then each block's states from its first (``ad^j``); the same sums in another order, so
    about ``2 sqrt(steps)`` numpy operations instead of one per step."""
    steps, n, sets = f.shape
    k = max(1, int(math.isqrt(steps)))
    blocks = -(-steps // k)
    padded = np.zeros((blocks * k, n, sets))
    padded[:steps] = f
    padded = padded.reshape(blocks, k, n, sets)
    local = np.empty_like(padded)  # local[b, j]: the state after step j + 1 of block b, from rest
    local[:, 0] = padded[:, 0]
    for j in range(1, k):
        local[:, j] = ad @ local[:, j - 1] + padded[:, j]
    powers = np.empty((k, n, n))  # ad^(j + 1)
    powers[0] = ad
    for j in range(1, k):
        powers[j] = ad @ powers[j - 1]
    starts = np.empty((blocks + 1, n, sets))  # the state at the start of every block
    starts[0] = x0
    for b in range(blocks):
        starts[b + 1] = powers[-1] @ starts[b] + local[b, -1]
    if not states:
        last = steps - (blocks - 1) * k - 1  # the last step's place in the last block
        return powers[last] @ starts[blocks - 1] + local[blocks - 1, last]
    x = np.empty((blocks * k + 1, n, sets))
    x[0] = x0
    x[1:] = (np.einsum("jik,bkl->bjil", powers, starts[:-1]) + local).reshape(blocks * k, n, sets)
    return x[:steps + 1]


def forced_response(sys: StateSpace, t: np.ndarray, u: np.ndarray, x0: np.ndarray | None = None,
                    outputs: bool = True) -> tuple[np.ndarray | None, np.ndarray]:
    """The response over the uniform grid ``t`` to inputs ``u`` linear between the samples.

    ``u``: ``(ninputs, len(t))``, or ``(ninputs, len(t), sets)`` for several sets of inputs at once;
    ``x0``: the initial state (``(nstates,)`` or ``(nstates, sets)``; default zero). Returns the
    outputs (shaped as ``u`` with ``noutputs`` rows; None when ``outputs`` is false) and the final state.
    """
    dt = _step(t)
    u = np.asarray(u, dtype=float)
    single = u.ndim == 2
    if single:
        u = u[:, :, None]
    ni, n, sets = u.shape
    if ni != sys.ninputs or n != len(t):
        raise ValueError(f"inputs of shape {u.shape[:2]} for {sys.ninputs} inputs over {len(t)} instants")
    ad, b0, b1 = hold_matrices(sys, dt)
    ns = sys.nstates
    # the inputs' share of every step at once; the state then follows x[i] = Ad x[i-1] + f[i-1]
    f = np.einsum("ij,jkl->kil", b0, u[:, :-1]) + np.einsum("ij,jkl->kil", b1, u[:, 1:])
    start = np.zeros((ns, sets)) if x0 is None else np.broadcast_to(
        np.asarray(x0, dtype=float).reshape(ns, -1), (ns, sets))
    if not outputs:
        end = linear_recurrence(ad, f, start, states=False)
        return None, end[:, 0] if single else end
    x = linear_recurrence(ad, f, start)
    y = np.einsum("ij,kjl->ikl", sys.C, x) + np.einsum("ij,jkl->ikl", sys.D, u)
    return (y[:, :, 0] if single else y), (x[-1, :, 0] if single else x[-1])


def periodic_steady_state(sys: StateSpace, t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Outputs of the periodic steady state over one period ``t`` (``u`` as in :func:`forced_response`).

    The state at the cycle start solves ``x0 = Phi x0 + x_forced(T)`` with the state transition
    ``Phi = exp(A T)`` (a stable system: ``I - Phi`` is invertible)."""
    _, free_end = forced_response(sys, t, u, outputs=False)
    phi = expm(sys.A * (t[-1] - t[0]))
    x0 = np.linalg.solve(np.eye(sys.nstates) - phi, free_end)
    y, _ = forced_response(sys, t, u, x0)
    return y


# --------------------------------------------------------------------------- loop margins


def _poly_iw_sqr(p: np.ndarray) -> np.ndarray:
    return np.real(np.polymul(p, p.conj()))


def stability_margins(num, den) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every gain margin, phase margin [deg] and modulus margin of the loop ``L(s) = num(s)/den(s)``
    (coefficients, highest power first): ``1/|L|`` where the phase crosses -180 degrees, the phase
    above -180 degrees where ``|L|`` crosses 1, ``|1 + L|`` at its local minima. Crossings are the
    positive real roots of polynomials in the frequency ``w``, as python-control's ``stability_margins``
    (``returnall=True``) finds them."""
    num = np.trim_zeros(np.atleast_1d(np.asarray(num, dtype=float)), "f")
    den = np.trim_zeros(np.atleast_1d(np.asarray(den, dtype=float)), "f")
    num_iw = (1j) ** np.arange(len(num) - 1, -1, -1) * num
    den_iw = (1j) ** np.arange(len(den) - 1, -1, -1) * den

    def loop(w):
        with np.errstate(all="ignore"):  # a root of den (an integrator at w = 0): not a margin
            return np.polyval(num, 1j * w) / np.polyval(den, 1j * w)

    def positive_roots(p, strict: bool):
        w = np.roots(p)
        w = np.real(w[np.isreal(w)])
        return np.sort(w[w > 0] if strict else w[w >= 0])

    # gain margin: the phase crosses -180 degrees (imag L = 0 and real L <= 0)
    w180 = positive_roots(np.polysub(np.polymul(num_iw.imag, den_iw.real), np.polymul(num_iw.real, den_iw.imag)),
                          strict=False)
    r180 = loop(w180)
    # on the negative real axis: python-control keeps ``r180 <= 0`` in numpy's order of complex numbers (the
    # real part first, then the imaginary part), stated here without relying on that order
    r180 = r180[(r180.real < 0.0) | ((r180.real == 0.0) & (r180.imag <= 0.0))]
    # phase margin: |L| = 1
    wc = positive_roots(np.polysub(_poly_iw_sqr(num_iw), _poly_iw_sqr(den_iw)), strict=True)
    # modulus margin: the minima of |1 + L|^2 = |num + den|^2 / |den|^2
    n2 = _poly_iw_sqr(np.polyadd(num_iw, den_iw))
    d2 = _poly_iw_sqr(den_iw)
    slope = np.polysub(np.polymul(np.polyder(n2), d2), np.polymul(np.polyder(d2), n2))
    ws = positive_roots(slope, strict=True)
    ws = ws[np.polyval(np.polyder(slope), ws) > 0.0]
    with np.errstate(all="ignore"):
        gm = 1.0 / np.abs(r180)
    pm = np.remainder(np.angle(loop(wc), deg=True), 360.0) - 180.0
    sm = np.abs(loop(ws) + 1.0)
    return gm, pm, sm
