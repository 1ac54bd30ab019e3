"""Load torque, sizing checks, the catalogue ranking, the fastest stitch rate and the inertia-matching optimum."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from strokeopt import Check, DriveLimits, Load, LoadForce, ProblemError, CrankSlider, load_problem, load_torque
from strokeopt.drive.catalogue import load_catalogue
from strokeopt.drive.checks import BeltSpec, belt_load, binding_check, drive_checks
from strokeopt.drive.sizing import max_spm, optimal_radius, scale_kinematics, size_drive


@pytest.fixture(scope="module")
def cat():
    return load_catalogue()


@pytest.fixture(scope="module")
def sized600(reference):
    return size_drive(reference, 600)


# thesis Tab. 4.4: modified sine chi = 0.095, 500 spm, move 1: pitch diameter [mm] -> peak torque [N m]
TAB_4_4 = [(28, 26.74, 1.17), (36, 34.38, 1.27), (48, 45.84, 1.47)]


@pytest.mark.parametrize("teeth, pd_mm, torque", TAB_4_4)
def test_tab_4_4_peak_torque(reference, teeth, pd_mm, torque):
    # thesis Tab. 4.4, within 3 %; motor 055U2B30 (the thesis's), moving mass from the problem file
    s = size_drive(reference, 500, motors=["055U2B30"], teeth=[teeth])
    c = s.candidates[0]
    assert c.pulley.pitch_diameter * 1e3 == pytest.approx(pd_mm, abs=0.005)
    assert c.check("peak_torque").value == pytest.approx(torque, rel=0.03)
    # the peak falls in move 1 (21.0-58.8 deg with the published times)
    assert 21.0 <= c.peak_angle_deg <= 58.8


def test_larger_pulleys_need_more_torque(reference):
    # thesis 4.5: "larger pulleys need less angular acceleration but more torque"
    s = size_drive(reference, 500, motors=["055U2B30"], teeth=[28, 36, 48])
    by_teeth = {c.pulley.teeth: c for c in s.candidates}
    peaks = [by_teeth[z].check("peak_torque").value for z in (28, 36, 48)]
    speeds = [by_teeth[z].check("peak_speed").value for z in (28, 36, 48)]
    assert peaks == sorted(peaks) and speeds == sorted(speeds, reverse=True)


def test_peak_speed_at_600_spm(sized600):
    # thesis 4.6: peak motor speed at 600 spm with PD 26.74 mm: 1861 rpm
    c = next(c for c in sized600.candidates if c.pulley.teeth == 28)
    assert c.check("peak_speed").value == pytest.approx(1861, abs=1.0)


def test_appendix_2_belt_numbers(cat):
    # thesis appendix 2: T_e = m_total (g + a_max), m_total = 0.208 kg, a_max = 545 m/s^2 -> 115.4 N;
    # S = 1.5 -> 173.1 N; with the thesis's 148.5 N for 28 grooves the width factor is 1.166 <= 1.66;
    # breaking 1.6 * T_e * 8 = 1477 N < 1990 N (3MR-9, glass cord)
    spec = BeltSpec(cat.belts["GT3-3MR-09"], cat.belt_methods["GT3"], service_factor=1.7 + 0 + 0 - 0.2,
                    cord="glass", allowable_tension=148.5)
    bl = belt_load(0.208 * (9.81 + 545), 28, spec)
    assert round(bl.peak_tension, 1) == 115.4
    assert round(bl.design_tension, 1) == 173.1
    assert round(bl.required_width_factor, 3) == 1.166
    assert round(bl.breaking_load) == 1477
    assert bl.required_width_factor <= spec.belt.width_factor  # 9 mm belt OK
    assert bl.required_width_factor > cat.belts["GT3-3MR-06"].width_factor  # 6 mm would not be
    assert bl.breaking_load < spec.belt.breaking_tension["glass"]
    # without the override the catalogue's row below 28 grooves (24: 146 N) is used: more conservative
    default = belt_load(bl.peak_tension, 28, BeltSpec(spec.belt, spec.method, 1.5))
    assert default.allowable_tension == 146 and default.required_width_factor > bl.required_width_factor


def test_torque_terms_add_up_and_symbolic_equals_numeric(reference, cat):
    spec = reference.drive
    motor = cat.motor("055U2B30")
    tr = cat.pulleys["GT3-28"].transmission()
    k = reference.stroke(600).sample(721)
    terms = load_torque(motor, tr, spec.load, k.s, k.v, k.a)
    parts = sum(np.broadcast_to(v, k.s.shape) for v in terms.as_dict().values())
    assert parts == pytest.approx(terms.total, abs=1e-12)
    assert terms.omega == pytest.approx(k.v / tr.radius)
    # the same function on CasADi symbols: one code path for both
    s, v, a = (ca.SX.sym(n) for n in "sva")
    sym = load_torque(motor, tr, spec.load, s, v, a)
    fn = ca.Function("T", [s, v, a], [sym.total, sym.load_force])
    tot, force = (np.asarray(o).ravel() for o in fn.map(len(k.s))(k.s[None, :], k.v[None, :], k.a[None, :]))
    assert tot == pytest.approx(terms.total, rel=1e-12, abs=1e-12)
    assert force == pytest.approx(terms.load_force, rel=1e-12, abs=1e-12)


def test_spring_and_gravity_terms(reference, cat):
    spec = reference.drive
    tr = cat.pulleys["GT3-28"].transmission()
    r = tr.radius
    # at rest in the lower dwell (handover, s = 0): gravity and the spring k2 only
    zero = np.zeros(1)
    terms = load_torque(0.0, tr, spec.load, zero, zero, zero)
    spring = 15.39 + 900 * 9e-3  # sources A.6: preload 900 N/m * 17.1 mm, plus 9 mm past the stop
    assert terms.forces["needle-bar spring k2"] == pytest.approx(-spring * r)
    assert terms.gravity == pytest.approx(0.191 * 9.81 * r)
    assert terms.total == pytest.approx((0.191 * 9.81 - spring) * r)
    # above the stop position the spring does not act on the bar
    above = load_torque(0.0, tr, spec.load, np.array([0.02]), zero, zero)
    assert above.forces["needle-bar spring k2"] == pytest.approx(0.0)


def test_power_balance_through_a_crank():
    # no special case for position-dependent transmissions: with inertia only,
    # motor power = d/dt kinetic energy = J omega eps + m v a
    tr = CrankSlider(0.01, 0.04, inertia=2e-5)
    load = Load(0.3)
    t = np.linspace(0.0, 0.1, 201)
    phi = 0.3 + 2.0 * t / 0.1 + 0.2 * np.sin(30 * t)
    omega = 20 + 6 * np.cos(30 * t)
    eps = -180 * np.sin(30 * t)
    x, mu, nu = tr.transfer(phi)
    v, a = mu * omega, mu * eps + nu * omega**2
    terms = load_torque(3e-5, tr, load, x, v, a)
    assert terms.total * omega == pytest.approx((3e-5 + 2e-5) * omega * eps + 0.3 * v * a, rel=1e-8, abs=1e-9)


def test_rms_uses_the_whole_cycle(reference, cat):
    spec = reference.drive
    motor = cat.motor("055U2B30")
    tr = cat.pulleys["GT3-28"].transmission()
    stroke = reference.stroke(600)
    k = stroke.sample(3601)
    checks = {c.name: c for c in drive_checks(motor, tr, spec.load, k.t, k.s, k.v, k.a)}
    fine = stroke.sample(40_001)
    torque = load_torque(motor, tr, spec.load, fine.s, fine.v, fine.a).total
    assert checks["rms_torque"].value == pytest.approx(np.sqrt(np.mean(torque**2)), rel=2e-3)
    # the dwells count: the spring and gravity hold torque through the lower dwell
    sch = reference.timing.schedule(600)
    dwell = (k.t > sch.t_start[2]) & (k.t < sch.t_start[3])
    held = load_torque(motor, tr, spec.load, k.s[dwell], k.v[dwell], k.a[dwell]).total
    assert np.all(np.abs(held) > 0.2)
    moves_only = np.sqrt(np.mean(load_torque(motor, tr, spec.load, k.s, k.v, k.a).total[~dwell] ** 2))
    assert checks["rms_torque"].value != pytest.approx(moves_only, rel=0.01)


def test_checks_and_margins():
    ok, bad = Check("a", 1.0, 4.0, "N m"), Check("b", 5.0, 4.0, "N m")
    assert ok.ok and ok.margin == pytest.approx(0.75)
    assert not bad.ok and bad.margin == pytest.approx(-0.25)
    assert binding_check([ok, bad]) is bad
    assert Check("c", 1.0, 0.0, "-").margin == -math.inf
    # at the limit within rounding (a speed scaled by a rate ratio lands a few last places above it)
    assert Check("speed", 4000.0 * (1 + 4e-16), 4000.0, "rpm").ok
    assert not Check("speed", 4000.0 * (1 + 1e-9), 4000.0, "rpm").ok


def test_max_spm_reaches_a_speed_limit_exactly():
    """A pair limited by its speed alone runs up to the rate where the speed meets the limit, that rate included
    (the loom's DT4 motor: 3200 rpm at 200 spm against its 4000 rpm is 250 spm, not 249)."""
    problem = load_problem(Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_sixbar.toml")
    sizing = size_drive(problem, motors=["DT4-2-10-Rx0-5000"], find_max_spm=True)
    row = next(c for c in sizing.candidates if c.pulley.name == "planetary-160-i16")
    speed = next(c for c in row.checks if c.name == "peak_speed")
    assert (speed.value, speed.limit) == pytest.approx((3200.0, 4000.0), rel=1e-9)
    assert row.max_spm == 250 and row.max_spm_binding == "peak_speed"


def test_catalogue_table_is_traceable(sized600, cat):
    cands = sized600.candidates
    assert len(cands) == 7 * 20
    assert {c.motor.name for c in cands} == set(cat.motors)
    # ranking: feasible first, then by overload
    feas = [c.feasible for c in cands]
    assert feas == sorted(feas, reverse=True)
    first = [c.check("overload").value for c in cands if c.feasible]
    assert first == sorted(first)
    for c in cands:
        peak = c.check("peak_torque").value
        assert c.check("overload").value == pytest.approx(100 * peak / c.motor.rated_torque)
        assert c.check("inertia_ratio").value == pytest.approx(
            (c.pulley.inertia + 0.191 * c.pulley.radius**2) / c.motor.rotor_inertia)
        assert sum(v for k, v in c.peak_terms.items() if k != "total") == pytest.approx(c.peak_terms["total"])
        assert abs(c.peak_terms["total"]) == pytest.approx(peak)
        assert c.binding == binding_check(c.checks).name
        assert c.feasible == all(ch.ok for ch in c.checks)
    # the thesis's motor is feasible with its pulley at 600 spm, overload = peak / rated
    c = next(c for c in cands if c.motor.name == "055U2B30" and c.pulley.teeth == 28)
    assert c.feasible


def test_scaling_the_stroke_equals_resampling(reference):
    k500 = reference.stroke(500).sample(1201)
    k650 = reference.stroke(650).sample(1201)
    scaled = scale_kinematics(k500, 650 / 500)
    for a, b in ((scaled.t, k650.t), (scaled.s, k650.s), (scaled.v, k650.v), (scaled.a, k650.a)):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9 * np.max(np.abs(b)))


def test_max_spm_is_the_edge_of_feasibility(reference, cat):
    spec = reference.drive
    belt = spec.belt_spec(cat)
    motor, pulley = cat.motor("055U2B30"), cat.pulleys["GT3-48"]
    k = reference.stroke(600).sample(3601)
    best, binding = max_spm(k, 600, motor, pulley, spec.load, spec.limits, belt, resolution=1.0)
    assert best is not None and 600 < best < 2000

    def checks(spm):
        kk = reference.stroke(spm).sample(3601)
        return drive_checks(motor, pulley.transmission(), spec.load, kk.t, kk.s, kk.v, kk.a, limits=spec.limits,
                            belt=belt, grooves=pulley.teeth)

    assert all(c.ok for c in checks(best))
    above = [c.name for c in checks(best + 1.0) if not c.ok]
    # the overload row is the drive's share of the one torque limit: it fails with peak_torque, never alone
    assert above[0] == binding and set(above) <= {binding, "overload"}
    # a tighter drive limit lowers it and makes the torque limit min(motor peak, 150 % x rated) bind
    tight = DriveLimits(peak_limit_pct=150.0, max_inertia_ratio=10.0)
    low, why = max_spm(k, 600, motor, pulley, spec.load, tight, belt)
    assert low < best and why == "peak_torque"
    kk = reference.stroke(low).sample(3601)
    limit = next(c for c in drive_checks(motor, pulley.transmission(), spec.load, kk.t, kk.s, kk.v, kk.a,
                                         limits=tight) if c.name == "peak_torque").limit
    assert limit == pytest.approx(min(motor.peak_torque, 1.5 * motor.rated_torque))


def test_max_spm_none_when_the_static_load_is_too_much(cat):
    # a constant force alone (200 N on a 13.4 mm radius: 2.7 N m) exceeds the rated torque: no rate is feasible
    problem_load = Load(0.01, -9.81, (LoadForce("press", "constant", -1.0, 200.0),))
    from strokeopt.motion.stroke import Kinematics

    t = np.linspace(0, 0.2, 11)
    z = np.zeros_like(t)
    best, why = max_spm(Kinematics(t, z + 0.01, z, z, z), 600, cat.motor("055U2B30"), cat.pulleys["GT3-28"],
                        problem_load, DriveLimits())
    assert best is None and why == "rms_torque"


def test_inertia_matching_optimum(reference, cat):
    # docs/architecture.md known optimum: fixed motion, inertia-only load: (J/r + m r) a is smallest at r = sqrt(J/m)
    k = reference.stroke(600).sample(3601)
    motor = cat.motor("055U2B30")
    load = Load(0.191)
    opt = optimal_radius(motor, load, k)
    assert opt.radius == pytest.approx(math.sqrt(motor.rotor_inertia / 0.191), rel=1e-6)
    a_max = np.max(np.abs(k.a))
    assert opt.peak_torque == pytest.approx(2 * math.sqrt(motor.rotor_inertia * 0.191) * a_max, rel=1e-6)
    # property: any other radius needs more peak torque
    from strokeopt import BeltPulley

    for f in (0.8, 0.95, 1.05, 1.25):
        other = load_torque(motor, BeltPulley(2 * f * opt.radius), load, k.s, k.v, k.a).total
        assert np.max(np.abs(other)) > opt.peak_torque
    # with the pulley's own inertia (catalogue model) the optimum moves to a smaller radius
    full = optimal_radius(motor, load, k, lambda d: cat.pulley_inertia("GT3", d))
    assert full.radius < opt.radius and full.pulley_inertia > 0


def test_drive_section_errors(write_problem):
    cases = [
        (lambda t: t.replace('gravity = "down"', 'gravity = "sideways"'), "drive.gravity", "not one of"),
        (lambda t: t.replace("pulley_teeth_max = 52", "pulley_teeth_max = 10"), "drive.pulley_teeth_max", "below"),
        (lambda t: t.replace("moving_mass_kg = 0.191", "moving_mass_kg = 0.191\nmoving_mas_kg = 1"),
         "drive.moving_mas_kg", "unknown field"),
        (lambda t: t.replace('kind = "spring"', 'kind = "sprung"'), "drive.load_forces[1].kind", "not one of"),
        (lambda t: t.replace("moving_mass_kg = 0.191", "moving_mass_kg = 0"), "drive.moving_mass_kg", "plausible range [0.0001, 1000]"),
        (lambda t: t.replace("[drive]\n", '[drive]\ncatalogues = ["nowhere.toml"]\n'), "drive.catalogues", "not found"),
    ]
    for edit, fld, words in cases:
        with pytest.raises(ProblemError) as info:
            load_problem(write_problem(edit))
        assert info.value.field == fld and words in info.value.message, (fld, str(info.value))


def test_size_without_a_drive_section(write_problem):
    text_cut = lambda t: t[: t.index("# ----", t.index("[transmission]"))] + t[t.index("# ----", t.index("[drive]")):]  # noqa: E731
    p = load_problem(write_problem(text_cut))
    assert p.drive is None
    with pytest.raises(ProblemError) as info:
        size_drive(p, 600)
    assert info.value.field == "drive"


def test_load_force_constant_and_downward_spring():
    push = LoadForce("press", "constant", -1.0, 5.0)
    assert push(np.array([0.0, 1.0])) == pytest.approx([-5.0, -5.0])
    spring = LoadForce("stop", "spring", -1.0, 2.0, 100.0, 0.01)
    assert spring(np.array([0.0, 0.02])) == pytest.approx([0.0, -(2.0 + 100.0 * 0.01)])


def test_problem_catalogue_files_are_relative_to_the_problem(write_problem, tmp_path):
    (tmp_path / "parts.toml").write_text(
        '[[motor]]\nname = "tiny"\nrated_speed_rpm = 6000\nrated_torque_N_m = 0.3\nstall_torque_N_m = 0.35\n'
        'peak_torque_N_m = 0.9\nrotor_inertia_kg_cm2 = 0.05\n', encoding="utf-8")
    p = load_problem(write_problem(lambda t: t.replace("[drive]\n", '[drive]\ncatalogues = ["parts.toml"]\n')))
    s = size_drive(p, 600, motors=["tiny"], teeth=[28])
    c = s.candidates[0]
    assert c.motor.name == "tiny" and not c.feasible  # 0.3 N m rated cannot hold the spring and gravity
    assert c.check("rms_torque").value > 0.3
