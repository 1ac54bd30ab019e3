"""The servo loop in numpy (servo/lti.py, servo/loop.py) against python-control and scipy, where they are
installed: the same loop, the same responses, the same margins and the same tuned gains. The command's
servo path imports neither of them."""

from __future__ import annotations

import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from strokeopt.servo import loop as servo_loop
from strokeopt.servo.lti import (expm, forced_response, linear_recurrence, pade, pade_delay,
                                 periodic_steady_state)
from strokeopt.servo.plant import axis_from_problem

control = pytest.importorskip("control")


@pytest.fixture(scope="module")
def setup(reference):
    settings = reference.servo
    axis = axis_from_problem(reference, settings)
    return reference, settings, axis, servo_loop.tune(axis, settings)


def control_loop(axis, settings, gains):
    """The closed loop as python-control interconnects it (plant, Padé delay, controller)."""
    j, r, m = axis.motor_inertia, axis.radius, axis.mass
    b = np.array([[0, 0], [1 / j, 0], [0, 0], [0, 1 / m]])
    cmat = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [r, 0, -1, 0], [0, 0, 1, 0]])
    plant = control.ss(axis.state_matrix(), b, cmat, np.zeros((4, 2)), inputs=["tau", "F_ext"],
                       outputs=["theta", "omega", "stretch", "x"], name="plant")
    num, den = control.pade(settings.sum_small_time_constants, settings.pade_order)
    delay = control.tf2ss(control.tf(num, den), inputs=["tau_cmd"], outputs=["tau"], name="delay")
    kp, kv, ti = gains.position_gain, gains.speed_gain, gains.speed_integral_time
    row = np.array([[kp, 1.0, 0.0, -kp, -1.0]])
    ctrl = control.ss(np.zeros((1, 1)), row, np.array([[kv / ti]]), kv * row + np.array([[0, 0, 1.0, 0, 0]]),
                      inputs=["theta_ref", "omega_ff", "tau_ff", "theta", "omega"], outputs=["tau_cmd"],
                      name="controller")
    names = ["theta_ref", "omega_ff", "tau_ff", "F_ext"]
    outs = ["theta", "stretch", "x", "tau_cmd"]
    return control.ss(control.interconnect([plant, delay, ctrl], inplist=names, outlist=outs, inputs=names,
                                           outputs=outs))


def control_margins(axis, settings, gains) -> dict:
    """The margins as python-control finds them on its own loop transfer function."""
    b = [[0], [1 / axis.motor_inertia], [0], [0]]
    plant = control.ss2tf(control.ss(axis.state_matrix(), b, [[0, 1, 0, 0]], 0))
    num, den = control.pade(settings.sum_small_time_constants, settings.pade_order)
    s = control.tf("s")
    pi = gains.speed_gain * (1 + 1 / (gains.speed_integral_time * s))
    open_loop = control.minreal(pi * (1 + gains.position_gain / s) * plant * control.tf(num, den), verbose=False)
    gms, pms, sms, *_ = control.stability_margins(open_loop, returnall=True)
    up = [float(g) for g in np.atleast_1d(gms) if g > 1]
    return {"gain_margin": min(up) if up else math.inf, "phase_margin_deg": min(np.atleast_1d(pms), default=math.inf),
            "modulus_margin": min(np.atleast_1d(sms), default=math.inf)}


def frequency_response(sys, w: float) -> np.ndarray:
    a, b, c, d = (np.asarray(x) for x in (sys.A, sys.B, sys.C, sys.D))
    return c @ np.linalg.solve(1j * w * np.eye(a.shape[0]) - a, b) + d


@pytest.mark.parametrize("delay, order", [(0.5e-3, 3), (1e-3, 1), (2e-4, 5), (1e-3, 8)])
def test_pade_is_python_controls(delay, order):
    num, den = pade(delay, order)
    ref_num, ref_den = control.pade(delay, order)
    assert np.allclose(num, ref_num, rtol=1e-13, atol=0) and np.allclose(den, ref_den, rtol=1e-13, atol=0)
    ss = pade_delay(delay, order)
    ref = control.tf(ref_num, ref_den)
    for w in (1.0, 1e2, 1e4, 1e6):
        assert frequency_response(ss, w)[0, 0] == pytest.approx(complex(ref(1j * w)), rel=1e-12)


def test_expm_is_scipys():
    scipy_linalg = pytest.importorskip("scipy.linalg")
    rng = np.random.default_rng(1)
    for scale in (1e-3, 0.1, 1.0, 10.0, 50.0):
        a = rng.normal(size=(12, 12)) * scale - 2 * scale * np.eye(12)
        ref = scipy_linalg.expm(a)
        assert np.max(np.abs(expm(a) - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_linear_recurrence_is_the_step_by_step_one():
    rng = np.random.default_rng(0)
    ad = expm(rng.normal(size=(6, 6)) * 0.01 - 0.05 * np.eye(6))
    for steps in (1, 2, 5, 17, 1001):
        f, x0 = rng.normal(size=(steps, 6, 3)), rng.normal(size=(6, 3))
        x = [x0]
        for i in range(steps):
            x.append(ad @ x[-1] + f[i])
        assert np.allclose(linear_recurrence(ad, f, x0), np.array(x), rtol=0, atol=1e-13)
        assert np.allclose(linear_recurrence(ad, f, x0, states=False), x[-1], rtol=0, atol=1e-13)


def test_the_loop_is_python_controls_loop(setup):
    _, settings, axis, gains = setup
    ours = servo_loop.build_loop(axis, settings, gains)
    ref = control_loop(axis, settings, gains)
    for w in (0.1, 10.0, 1e3, 3e3, 2e4):  # the same transfer functions, input by input and output by output
        h, h_ref = frequency_response(ours.system, w), frequency_response(ref, w)
        assert np.allclose(h, h_ref, rtol=1e-10, atol=1e-12 * np.max(np.abs(h_ref)))
    assert np.allclose(np.sort_complex(ours.poles), np.sort_complex(np.linalg.eigvals(ref.A)), rtol=1e-8)


def test_responses_are_python_controls(setup):
    _, settings, axis, gains = setup
    sys_ = servo_loop.build_loop(axis, settings, gains).system
    t = np.arange(0, 0.05, 1e-5)
    u = np.vstack([np.sin(200 * t), np.cos(300 * t), 1e-3 * np.sin(50 * t), 10 * np.cos(20 * t)])
    ref = control.ss(sys_.A, sys_.B, sys_.C, sys_.D)
    y_ref = np.asarray(control.forced_response(ref, t, u).outputs)
    y, _ = forced_response(sys_, t, u)
    scale = np.max(np.abs(y_ref), axis=1, keepdims=True)
    assert np.max(np.abs(y - y_ref) / scale) < 1e-8
    # several sets of inputs at once: each as if alone
    both, _ = forced_response(sys_, t, np.stack([u, -2 * u], axis=-1))
    assert np.max(np.abs(both[:, :, 0] - y) / scale) < 1e-12 and np.max(np.abs(both[:, :, 1] + 2 * y) / scale) < 1e-12
    # the periodic steady state repeats itself
    tp = np.linspace(0.0, 2 * np.pi / 100, 2001)
    up = np.vstack([np.sin(100 * tp), np.cos(100 * tp), np.zeros_like(tp), np.sin(200 * tp)])
    yp = periodic_steady_state(sys_, tp, up)
    assert np.allclose(yp[:, 0], yp[:, -1], rtol=0, atol=1e-9 * np.max(np.abs(yp)))


def test_the_loop_response_is_the_one_python_control_simulates(setup):
    _, settings, axis, gains = setup
    period = 0.24
    sys_ = servo_loop.build_loop(replace(axis, load=None), settings, gains).system
    step = min(settings.position_sampling / 25, period / 4000)
    t = np.arange(0.0, period + step / 2, step)  # one cycle on the simulation's step
    td = np.clip(t - settings.sum_small_time_constants, 0.0, None)
    s_ref = td**2 / 2
    u = np.vstack([s_ref / axis.radius, td / axis.radius, axis.total_inertia / axis.radius * np.ones_like(t), 0 * t])
    x = np.asarray(control.forced_response(control.ss(sys_.A, sys_.B, sys_.C, sys_.D), t, u).outputs)[2]
    ours, _ = forced_response(sys_, t, u)
    # the error is a small difference of two large numbers (s_ref - x, 1e-5 of them at the end): both agree
    # with the error from the exact matrices in extended precision to 4e-8 (python-control) and 4e-9 (ours)
    assert np.max(np.abs(ours[2] - x)) <= 1e-7 * np.max(np.abs(s_ref - x))


def test_accuracy_is_the_one_python_control_simulates(reference, setup, monkeypatch):
    # the same loop's periodic steady state by python-control and scipy: the same handover error to 1e-9
    from strokeopt.servo import accuracy

    scipy_linalg = pytest.importorskip("scipy.linalg")
    _, settings, axis, gains = setup

    def periodic(sys_, t, *inputs):
        ref = control.ss(sys_.A, sys_.B, sys_.C, sys_.D)
        phi = scipy_linalg.expm(sys_.A * (t[-1] - t[0]))
        out = []
        for u in inputs:
            free = control.forced_response(ref, t, u, initial_state=np.zeros(sys_.nstates), return_states=True)
            x0 = np.linalg.solve(np.eye(sys_.nstates) - phi, free.states[:, -1])
            out.append(np.asarray(control.forced_response(ref, t, u, initial_state=x0).outputs))
        return out

    ours = accuracy.handover_accuracy(reference, spm=910, settings=settings, axis=axis, gains=gains)
    monkeypatch.setattr(accuracy, "periodic_response", periodic)
    ref = accuracy.handover_accuracy(reference, spm=910, settings=settings, axis=axis, gains=gains)
    assert ours.handover_error == pytest.approx(ref.handover_error, rel=1e-9)
    for name in ("x", "servo", "belt", "belt_load", "tau_cmd", "error_load"):
        a, b = getattr(ours, name), getattr(ref, name)
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), name


@pytest.mark.parametrize("stiffness", [1.0, 0.3, 10.0])
def test_margins_are_python_controls(setup, stiffness):
    _, settings, axis, gains = setup
    axis = replace(axis, belt_stiffness=axis.belt_stiffness * stiffness,
                   belt_damping=axis.belt_damping * math.sqrt(stiffness))
    ours, ref = servo_loop.loop_margins(axis, settings, gains), control_margins(axis, settings, gains)
    for key in ours:
        assert ours[key] == pytest.approx(ref[key], rel=1e-9), key


def test_tuned_gains_are_those_of_python_controls_margins(reference, setup, monkeypatch):
    # the tuning rule's bisection takes the same decision at every step: the same gains, bit for bit
    _, settings, _, _ = setup
    motors = reference.drive.catalogue().motors
    cases = [(motors[name], teeth) for name in motors for teeth in (14, 28, 52)]
    ours = [servo_loop.tune(axis_from_problem(reference, settings, motor=m, pulley_teeth=z), settings)
            for m, z in cases]
    monkeypatch.setattr(servo_loop, "loop_margins", control_margins)
    ref = [servo_loop.tune(axis_from_problem(reference, settings, motor=m, pulley_teeth=z), settings)
           for m, z in cases]
    assert ours == ref


def test_the_servo_path_imports_neither_python_control_nor_scipy(tmp_path):
    code = ("import runpy, sys; sys.argv = ['strokeopt', 'solve', 'problems/deco2000_needle_bar.toml', '--json', "
            "'--plot', 'none']\ntry:\n    runpy.run_module('strokeopt', run_name='__main__')\nexcept SystemExit as e:\n"
            "    code = e.code\nprint(code, *sorted(m for m in ('control', 'scipy', 'matplotlib') if m in sys.modules),"
            " file=sys.stderr)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=str(Path(__file__).resolve().parents[2]))
    assert done.stderr.strip().splitlines()[-1] == "0", done.stderr[-500:]
