"""Transmissions: position functions, AD transfer functions, inverses, numeric and symbolic paths."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from strokeopt import BeltPulley, ScrewLever, CrankSlider, gt3_pitch_diameter
from strokeopt.drive.transmission import Transmission

PHI = np.linspace(0.1, 2.9, 15)


def test_gt3_pitch_diameters():
    # thesis 4.2: z = 28 -> 26.74 mm, 36 -> 34.38 mm, 48 -> 45.84 mm
    for z, pd in ((28, 26.74), (36, 34.38), (48, 45.84)):
        assert gt3_pitch_diameter(z) * 1e3 == pytest.approx(pd, abs=0.005)


def test_one_pulley_concept_problem_catalogue_and_toothed(reference):
    """The problem's transmission, a catalogue pulley's and BeltPulley.toothed are the same pulley."""
    from strokeopt.drive.catalogue import load_catalogue

    tr = reference.transmission
    assert (tr.teeth, tr.profile, reference.pulley_teeth) == (28, "GT3", 28)
    assert tr.pitch_diameter == gt3_pitch_diameter(28) and tr.inertia == 0.0  # the ideal drive: no pulley inertia
    cat = load_catalogue()
    from_cat = cat.pulleys["GT3-28"].transmission()
    assert (from_cat.teeth, from_cat.profile) == (28, "GT3")
    assert from_cat.pitch_diameter == tr.pitch_diameter == cat.pulleys["GT3-28"].pitch_diameter
    assert from_cat.inertia == cat.pulleys["GT3-28"].inertia > 0
    z36 = BeltPulley.toothed(36, inertia=from_cat.inertia)
    assert (z36.teeth, z36.profile, z36.inertia) == (36, "GT3", from_cat.inertia)
    assert z36.pitch_diameter == cat.pulleys["GT3-36"].pitch_diameter
    assert BeltPulley(0.02).teeth is None


def test_belt_fast_path_equals_the_ad_transfer_functions():
    belt = BeltPulley(0.02674, inertia=1.6e-6)
    fast = belt.transfer(PHI)
    ad = Transmission.transfer(belt, PHI)  # the base class: CasADi AD of the position function
    for f, a in zip(fast, ad):
        assert f == pytest.approx(a, rel=1e-12, abs=1e-15)
    assert fast[1] == pytest.approx(belt.radius) and np.all(fast[2] == 0)
    assert belt.inertia == 1.6e-6


def test_belt_rejects_bad_sizes():
    with pytest.raises(ValueError):
        BeltPulley(0.0)
    with pytest.raises(ValueError):
        BeltPulley(0.02, inertia=-1.0)


@pytest.mark.parametrize("tr", [CrankSlider(0.01, 0.04), ScrewLever(2e-3, 15e-3, 25e-3, offset=0.2)],
                         ids=["crank", "screw_lever"])
def test_inverse_and_transfer_functions(tr):
    x, mu, nu = tr.transfer(PHI)
    assert tr.motor_angle(x) == pytest.approx(PHI, rel=1e-9)
    # transfer functions against central differences of the position function
    h = 1e-5
    xp, xm = tr.transfer(PHI + h)[0], tr.transfer(PHI - h)[0]
    assert mu == pytest.approx((xp - xm) / (2 * h), rel=1e-6)
    assert nu == pytest.approx((xp - 2 * x + xm) / h**2, rel=1e-4, abs=1e-7)


@pytest.mark.parametrize("tr", [BeltPulley(0.03), CrankSlider(0.01, 0.04), ScrewLever(2e-3, 15e-3, 25e-3, 0.2)],
                         ids=["belt", "crank", "screw_lever"])
def test_motor_kinematics_inverts_the_load_motion(tr):
    # a motor motion phi(t) -> load motion by the chain rule -> back to the motor motion
    t = np.linspace(0.0, 0.05, 11)
    phi = 0.5 + 1.5 * t / 0.05 + 0.1 * np.sin(40 * t)
    omega = 1.5 / 0.05 + 4 * np.cos(40 * t)
    eps = -160 * np.sin(40 * t)
    x, mu, nu = tr.transfer(phi)
    v, a = mu * omega, mu * eps + nu * omega**2
    p2, w2, e2 = tr.motor_kinematics(x, v, a)
    assert p2 == pytest.approx(phi, rel=1e-9)
    assert w2 == pytest.approx(omega, rel=1e-9)
    assert e2 == pytest.approx(eps, rel=1e-7, abs=1e-6)
    # the same on CasADi symbols
    xs, vs, as_ = (ca.SX.sym(n) for n in "xva")
    fn = ca.Function("mk", [xs, vs, as_], list(tr.motor_kinematics(xs, vs, as_)))
    sym = [np.asarray(o).ravel() for o in fn.map(len(t))(x[None, :], v[None, :], a[None, :])]
    for s, n in zip(sym, (phi, omega, eps)):
        assert s == pytest.approx(n, rel=1e-7, abs=1e-6)


def test_screw_lever_transfer_function_is_the_product_of_the_stages():
    # sources B: mu24 = cos^2(phi4)/R0 (d phi4/d x2), mu46 = R0P/cos^2(phi4P) (d x6/d phi4P),
    # x2 = s/(2 pi) phi: mu = mu46 * mu24 * s/(2 pi)
    lead, r0, r0p, off = 2e-3, 15e-3, 25e-3, 0.2
    tr = ScrewLever(lead, r0, r0p, off)
    _, mu, _ = tr.transfer(PHI)
    x2 = lead / (2 * math.pi) * PHI
    phi4 = np.arctan(x2 / r0)
    mu24 = np.cos(phi4) ** 2 / r0
    mu46 = r0p / np.cos(phi4 + off) ** 2
    assert mu == pytest.approx(mu46 * mu24 * lead / (2 * math.pi), rel=1e-12)
    # nu24 = -2 cos^3 sin / R0^2 is d mu24 / d x2 (sources B)
    h = 1e-7
    num = (np.cos(np.arctan((x2 + h) / r0)) ** 2 - np.cos(np.arctan((x2 - h) / r0)) ** 2) / r0 / (2 * h)
    assert -2 * np.cos(phi4) ** 3 * np.sin(phi4) / r0**2 == pytest.approx(num, rel=1e-5)
    # without the offset the chain is linear: x6 = R0P/R0 * x2
    lin = ScrewLever(lead, r0, r0p)
    x, mu0, nu0 = lin.transfer(PHI)
    assert x == pytest.approx(r0p / r0 * x2, rel=1e-12)
    assert nu0 == pytest.approx(0.0, abs=1e-12)
