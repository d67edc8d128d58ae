"""``hsgran impact``: JSON and table output, physics seen through the command line, and bad input.

Most tests call :func:`hsgran.cli.main` in-process; one runs the real command in a subprocess to
prove the exit code and that no traceback reaches the user.

Frame of the command (hsgran/impact.py): wall normal +z, the sphere moves towards +x before
impact, spin about +y = n × t̂ is positive for forward rolling (topspin).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from hsgran import __version__
from hsgran.cli import main
from hsgran.errors import EXIT_BAD_INPUT
from tests.cli_errors import run_error

STEEL_ON_STEEL = ["impact", "--sphere", "steel", "--wall", "steel", "--radius", "0.005"]
#: Kharaz et al. 2001 / Chung & Ooi 2011 test 4 at 40° (VALIDATION.md, case CO4).
KHARAZ_40 = ["impact", "--sphere", "alumina", "--wall", "glass", "--radius", "0.0025",
             "--speed", "3.9", "--angle", "40", "--restitution", "0.98"]

RESULT_FIELDS = ("e_n", "stage", "regime", "captured", "velocity_after", "angular_velocity_after",
                 "normal_impulse", "tangential_impulse", "delta_max", "contact_radius_max",
                 "force_max", "energy_lost")


def _strict_constant(name):
    raise AssertionError(f"JSON output contains {name}: not strict JSON")


def run_json(capsys, *argv) -> dict:
    """Run ``hsgran ... --json`` in-process and parse its one JSON object."""
    assert main([*argv, "--json"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    return json.loads(out, parse_constant=_strict_constant)




# ---- JSON output ---------------------------------------------------------------------------

def test_json_steel_head_on_plasticity_reproduces_regression_anchor(capsys):
    # MODEL §7.1: steel sphere R = 5 mm on steel at 1 m/s.
    doc = run_json(capsys, *STEEL_ON_STEEL, "--speed", "1", "--angle", "0",
                   "--effects", "plasticity")
    for field in RESULT_FIELDS:
        assert field in doc
    assert len(doc["velocity_after"]) == 3
    assert len(doc["angular_velocity_after"]) == 3
    assert doc["e_n"] == pytest.approx(0.7901, abs=5e-5)
    assert doc["stage"] == "elastic-plastic"
    assert doc["regime"] == "none"
    assert doc["captured"] is False
    assert doc["delta_max"] == pytest.approx(1.326e-5, rel=1e-3)
    assert doc["force_max"] == pytest.approx(346.7, rel=1e-3)
    assert doc["contact_radius_max"] == pytest.approx(2.574e-4, rel=1e-3)
    assert doc["critical"]["speed_y"] == pytest.approx(0.1498, rel=1e-3)
    assert doc["critical"]["speed_p"] == pytest.approx(28.86, rel=1e-3)
    assert doc["velocity_after"] == pytest.approx([0.0, 0.0, doc["e_n"]], abs=1e-12)
    mass = 7800.0 * 4.0 / 3.0 * math.pi * 0.005**3
    assert doc["normal_impulse"] == pytest.approx((1.0 + doc["e_n"]) * mass, rel=1e-12)
    assert doc["energy_lost"] == pytest.approx(0.5 * mass * (1.0 - doc["e_n"] ** 2), rel=1e-9)
    assert doc["effects"] == ["plasticity"]
    inp = doc["input"]
    assert (inp["sphere"], inp["wall"], inp["other"]) == ("steel", "steel", None)
    assert (inp["radius"], inp["speed"], inp["angle"], inp["spin"]) == (0.005, 1.0, 0.0, 0.0)
    assert inp["velocity_before"] == pytest.approx([0.0, 0.0, -1.0])


def test_json_kharaz_alumina_on_glass_40_degrees_sliding(capsys):
    # VALIDATION.md CO4 at θ = 40°, built-in μ = 0.092: e_t = 0.7829 and ω′ = −544.2 rad/s in
    # Chung & Ooi's axes, where negative means forward rolling for a positive tangential
    # velocity. Here forward rolling is +y (n × t̂ = z × x), so ω′ = +544.2 about +y.
    doc = run_json(capsys, *KHARAZ_40)
    assert doc["input"]["contact"]["sliding_friction"] == 0.092
    assert doc["regime"] == "sliding"
    assert doc["stage"] == "fixed"
    assert doc["e_n"] == pytest.approx(0.98)
    assert doc["derived"]["e_t"] == pytest.approx(0.7829, abs=1e-4)
    wx, wy, wz = doc["angular_velocity_after"]
    assert wy == pytest.approx(544.2, abs=0.05)
    assert wx == 0.0
    assert wz == 0.0
    assert doc["velocity_after"][1] == 0.0
    assert doc["derived"]["rebound_angle"] == pytest.approx(33.84, abs=0.01)
    assert doc["derived"]["contact_patch_rebound_angle"] == pytest.approx(11.62, abs=0.01)
    # Prescribed restitution bypasses the deformation model: no deformation fields (null).
    assert doc["delta_max"] is None
    assert doc["stage_impulses"] == [None, None, None]


def test_json_sphere_sphere_conserves_linear_momentum(capsys):
    doc = run_json(capsys, "impact", "--sphere", "steel", "--other", "glass", "--radius", "0.004",
                   "--other-radius", "0.006", "--speed", "2", "--angle", "35", "--spin", "-80",
                   "--friction", "0.3")
    inp = doc["input"]
    assert inp["mode"] == "sphere-sphere"
    assert inp["wall"] is None
    m1 = inp["sphere_material"]["density"] * 4.0 / 3.0 * math.pi * 0.004**3
    m2 = inp["other_material"]["density"] * 4.0 / 3.0 * math.pi * 0.006**3
    before = [m1 * v for v in inp["velocity_before"]]
    pairs = zip(doc["velocity_after"], doc["other_velocity_after"], strict=True)
    after = [m1 * a + m2 * b for a, b in pairs]
    assert after == pytest.approx(before, rel=1e-12, abs=1e-15)
    # The resting sphere lies below: it is pushed down (−z) and forwards (+x, friction).
    assert doc["other_velocity_after"][2] < 0.0
    assert doc["other_velocity_after"][0] > 0.0
    assert doc["input"]["effective_radius"] == pytest.approx(1.0 / (1 / 0.004 + 1 / 0.006))


@pytest.mark.parametrize("spin", [150.0, -200.0])
def test_spin_acts_through_the_effective_angle(capsys, spin):
    # MODEL §4.3: the contact-point outcome depends only on u0 = v_t0 − R ω0, i.e. on
    # tan θ_eff = u0/v_n0. A spinning sphere and a non-spinning one at θ_eff with the same
    # normal speed get the same tangential impulse, slip after and spin change.
    radius, speed, angle = 0.005, 2.0, 45.0
    common = [*STEEL_ON_STEEL, "--friction", "0.1"]
    v_n0 = speed * math.cos(math.radians(angle))
    u0 = speed * math.sin(math.radians(angle)) - radius * spin
    spinning = run_json(capsys, *common, "--speed", str(speed), "--angle", str(angle),
                        "--spin", str(spin))
    effective = run_json(capsys, *common, "--speed", repr(math.hypot(v_n0, u0)),
                         "--angle", repr(math.degrees(math.atan2(u0, v_n0))))
    plain = run_json(capsys, *common, "--speed", str(speed), "--angle", str(angle))
    assert spinning["derived"]["slip_before"] == pytest.approx(u0, rel=1e-12)
    assert spinning["e_n"] == pytest.approx(effective["e_n"], rel=1e-12)
    assert spinning["regime"] == effective["regime"]
    assert spinning["tangential_impulse"] == pytest.approx(effective["tangential_impulse"],
                                                           rel=1e-12)
    assert spinning["derived"]["slip_after"] == pytest.approx(effective["derived"]["slip_after"],
                                                              abs=1e-12)
    assert spinning["derived"]["spin_change"] == pytest.approx(
        effective["derived"]["spin_change"], rel=1e-12)
    # ... and the spin does change the outcome: topspin 150 rad/s makes the sphere roll
    # (plain: sliding), backspin 200 rad/s leaves more slip.
    assert plain["regime"] == "sliding"
    if spin > 0:
        assert spinning["regime"] == "rolling"
        assert spinning["derived"]["slip_after"] == pytest.approx(0.0, abs=1e-12)
    else:
        assert spinning["derived"]["slip_after"] > plain["derived"]["slip_after"] + 0.5


def test_gravity_is_accepted_and_ignored(capsys):
    args = [*STEEL_ON_STEEL, "--speed", "1", "--angle", "0"]
    with_gravity = run_json(capsys, *args, "--effects", "gravity,plasticity")
    without = run_json(capsys, *args, "--effects", "plasticity")
    assert with_gravity["effects"] == ["plasticity"]
    assert with_gravity["velocity_after"] == without["velocity_after"]


def test_yield_stress_override_scales_the_yield_speed(capsys):
    # MODEL §3.2: V_y ∝ σ_y^(5/2) at fixed E*, R*, m*. The override applies to the sphere;
    # on a rigid wall the sphere's yield stress governs the pair.
    args = ["impact", "--sphere", "steel", "--wall", "rigid", "--radius", "0.005", "--speed", "1",
            "--angle", "0", "--effects", "plasticity"]
    base = run_json(capsys, *args)
    harder = run_json(capsys, *args, "--yield-stress", "2e9")
    ratio = harder["critical"]["speed_y"] / base["critical"]["speed_y"]
    assert ratio == pytest.approx(2.0**2.5, rel=1e-12)
    assert harder["input"]["sphere_material"]["yield_stress"] == 2e9
    assert harder["input"]["wall_material"]["yield_stress"] is None  # inf: never yields
    assert harder["e_n"] > base["e_n"]


def test_yield_stress_override_leaves_the_wall_alone(capsys):
    # The pair yields at the smaller yield stress (MODEL §2): a harder sphere on a 1 GPa
    # steel wall still yields at 1 GPa, and the table says which body governs.
    args = [*STEEL_ON_STEEL, "--speed", "1", "--angle", "0", "--effects", "plasticity"]
    base = run_json(capsys, *args)
    harder = run_json(capsys, *args, "--yield-stress", "2e9")
    assert harder["input"]["wall_material"]["yield_stress"] == 1e9
    assert harder["critical"]["speed_y"] == base["critical"]["speed_y"]
    assert main([*args, "--yield-stress", "2e9"]) == 0
    assert "governing yield stress (wall)" in capsys.readouterr().out


def test_effects_beyond_the_paper_act_only_when_named(capsys):
    """docs/model.md §3.11: below the yield speed a viscoelastic sphere loses energy (the
    series' leading term: 1 − e ≈ 1.153 X); §4.5: near normal incidence an elastic contact's
    tangential impulse is far from the rigid rule's (e_t ≠ 5/7)."""
    slow = ["impact", "--sphere", "steel", "--wall", "rigid", "--radius", "0.001", "--speed",
            "0.01", "--angle", "0", "--dissipative-constant", "2e-7"]
    assert run_json(capsys, *slow, "--effects", "plasticity")["e_n"] == 1.0
    damped = run_json(capsys, *slow, "--effects", "plasticity,viscoelastic_damping")
    assert 0.8 < damped["e_n"] < 1.0
    assert damped["input"]["sphere_material"]["dissipative_constant"] == 2e-7
    oblique = ["impact", "--sphere", "alumina", "--wall", "rigid", "--radius", "0.0025",
               "--speed", "3.9", "--angle", "10", "--friction", "0.092", "--restitution", "0.98"]
    rigid = run_json(capsys, *oblique, "--effects", "rotation,friction")
    elastic = run_json(capsys, *oblique, "--effects", "rotation,friction,tangential_compliance")
    assert rigid["derived"]["e_t"] == pytest.approx(5.0 / 7.0, rel=1e-12)
    # Chung & Ooi's DEM: 0.687 at 10.2° (tests/contact/test_compliance.py compares in full)
    assert elastic["derived"]["e_t"] == pytest.approx(0.698, abs=0.01)


def test_rolling_friction_and_work_of_adhesion_overrides_act(capsys):
    args = [*STEEL_ON_STEEL, "--speed", "0.05", "--angle", "20", "--spin", "100",
            "--friction", "0.3"]
    plain = run_json(capsys, *args)
    doc = run_json(capsys, *args, "--rolling-friction", "0.01", "--work-of-adhesion", "0.5")
    assert doc["input"]["contact"]["rolling_friction"] == 0.01
    assert doc["input"]["contact"]["work_of_adhesion"] == 0.5
    assert plain["rolling_impulse"] == 0.0
    assert plain["work_adhesion"] == 0.0
    assert doc["rolling_impulse"] > 0.0
    assert doc["work_adhesion"] > 0.0
    assert doc["e_n"] < plain["e_n"]


def test_materials_file_adds_materials_and_contacts(capsys, tmp_path):
    path = tmp_path / "mats.toml"
    path.write_text(
        "[materials.rubberish]\ndensity = 1200\nyoungs_modulus = 5e7\npoisson_ratio = 0.45\n"
        "yield_stress = 1e7\n\n"
        "[[contacts]]\nbetween = ['rubberish', 'steel']\nsliding_friction = 0.8\n")
    doc = run_json(capsys, "impact", "--sphere", "rubberish", "--wall", "steel", "--radius",
                   "0.01", "--speed", "1", "--angle", "30", "--materials", str(path))
    assert doc["input"]["contact"]["sliding_friction"] == 0.8
    assert doc["input"]["sphere_material"]["youngs_modulus"] == 5e7
    assert doc["input"]["materials_file"] == str(path)
    # --friction overrides the file's value.
    doc = run_json(capsys, "impact", "--sphere", "rubberish", "--wall", "steel", "--radius",
                   "0.01", "--speed", "1", "--angle", "30", "--materials", str(path),
                   "--friction", "0.05")
    assert doc["input"]["contact"]["sliding_friction"] == 0.05


# ---- table output, help, version -------------------------------------------------------------

def test_table_prints_key_quantities_and_reconstruction_note(capsys):
    assert main([*STEEL_ON_STEEL, "--speed", "1", "--angle", "0", "--effects", "plasticity"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    lines = out.rstrip("\n").splitlines()
    header = next(line for line in lines if line.startswith("quantity"))
    value_col = header.index("value")
    rows = {line[:value_col].strip(): line[value_col:].split() for line in lines
            if len(line) > value_col and line[value_col - 2:value_col] == "  "}
    assert rows["normal restitution e_n"] == ["0.790113", "-"]
    assert rows["stage"] == ["elastic-plastic"]
    assert rows["yield speed V_y"] == ["0.149832", "m/s"]
    assert rows["full-plasticity speed V_p"] == ["28.8553", "m/s"]
    assert rows["max normal force F_max"] == ["346.724", "N"]
    assert rows["normal impulse J_n"][-2:] == ["N", "s"]
    last = lines[-1]
    assert "[OURS]" in last
    for section in ("§3.3-3.4", "§3.8", "§5.2"):
        assert section in last


def test_impact_help_says_what_is_reconstructed(capsys):
    assert main(["impact", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "[OURS]" in out
    for section in ("§3.3-3.4", "§3.8", "§5.2"):
        assert section in out
    assert "--wall MAT" in out
    assert "--other-radius" in out


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"hsgran {__version__}"


# ---- bad input: one stderr line, exit code 2 ------------------------------------------------

_OK = [*STEEL_ON_STEEL, "--speed", "1", "--angle", "0", "--effects", "plasticity"]


def _replace(args: list[str], option: str, value: str) -> list[str]:
    out = list(args)
    out[out.index(option) + 1] = value
    return out


BAD_INPUTS = {
    "no command": ([], "missing command"),
    "unknown command": (["impct"], "invalid choice: 'impct'"),
    "unknown option": ([*_OK, "--frcition", "0.3"], "did you mean '--friction'"),
    "missing required options": (["impact", "--sphere", "steel"], "required: --radius"),
    "missing wall or other": (["impact", "--sphere", "steel", "--radius", "1", "--speed", "1",
                               "--angle", "0"], "one of the arguments --wall --other"),
    "wall and other": ([*_OK, "--other", "steel"], "not allowed with"),
    "option without its value": ([*_OK, "--radius"], "--radius: expected one argument"),
    "other without other-radius": (["impact", "--sphere", "steel", "--other", "steel",
                                    "--radius", "0.005", "--speed", "1", "--angle", "0",
                                    "--effects", "plasticity"], "--other-radius: missing value"),
    "other-radius with a wall": ([*_OK, "--other-radius", "0.01"], "--other-radius"),
    "unknown sphere material": (_replace(_OK, "--sphere", "steal"),
                                "--sphere: unknown material 'steal' (did you mean 'steel'?)"),
    "unknown wall material": (_replace(_OK, "--wall", "glas"), "--wall: unknown material"),
    "rigid sphere": (_replace(_OK, "--sphere", "rigid"), "--sphere: material 'rigid'"),
    "negative radius": (_replace(_OK, "--radius", "-0.005"),
                        "--radius: must be a finite number > 0, got '-0.005'"),
    "nan radius": (_replace(_OK, "--radius", "nan"),
                   "--radius: must be a finite number > 0, got 'nan'"),
    "inf speed": (_replace(_OK, "--speed", "inf"), "--speed: must be a finite number > 0"),
    "zero speed": (_replace(_OK, "--speed", "0"), "--speed: must be a finite number > 0"),
    "text speed": (_replace(_OK, "--speed", "fast"), "--speed: must be a finite number > 0"),
    "angle 90": (_replace(_OK, "--angle", "90"), "--angle: must be a finite number in [0, 90)"),
    "nan angle": (_replace(_OK, "--angle", "NaN"), "--angle: must be a finite number"),
    "-inf spin": ([*_OK, "--spin", "-inf"], "--spin: must be a finite number, got '-inf'"),
    "spin without rotation": ([*_OK, "--spin", "-1e2"], "--spin: a spin needs the 'rotation'"),
    "nan friction": ([*_OK, "--friction", "nan"], "--friction: must be a finite number >= 0"),
    "negative friction": ([*_OK, "--friction", "-0.1"], "--friction: must be a finite number"),
    "inf rolling friction": ([*_OK, "--rolling-friction", "inf"], "--rolling-friction: must be"),
    "restitution above 1": ([*_OK, "--restitution", "1.5"],
                            "--restitution: must be a finite number in [0, 1], got '1.5'"),
    "nan yield stress": ([*_OK, "--yield-stress", "nan"], "--yield-stress: must be a finite"),
    "inf work of adhesion": ([*_OK, "--work-of-adhesion", "inf"], "--work-of-adhesion: must"),
    "nan other radius": (["impact", "--sphere", "steel", "--other", "steel", "--radius", "0.005",
                          "--other-radius", "nan", "--speed", "1", "--angle", "0"],
                         "--other-radius: must be a finite number > 0, got 'nan'"),
    "unknown effect": (_replace(_OK, "--effects", "plasticity,frcition"),
                       "unknown effect 'frcition' (did you mean 'friction'?)"),
    "friction without rotation": (_replace(_OK, "--effects", "friction"),
                                  "effect 'friction' needs effect 'rotation'"),
    "friction unknown for the pair": (_OK[:-2], "pass --friction"),
    "materials file missing": ([*_OK, "--materials", "{tmp}/none.toml"],
                               "--materials: file not found"),
    "materials file syntax": ([*_OK, "--materials", "{tmp}/syntax.toml"], "TOML syntax error"),
    "poisson ratio 0.5 in a materials file": (
        ["impact", "--sphere", "jelly", "--wall", "steel", "--radius", "0.01", "--speed", "1",
         "--angle", "0", "--materials", "{tmp}/nu.toml"],
        "materials.jelly.poisson_ratio: must be in (-1, 0.5), got 0.5"),
    "unknown material in a materials file contact": (
        [*_OK, "--materials", "{tmp}/contact.toml"], "contacts[0].between: unknown material"),
}


@pytest.fixture
def bad_files(tmp_path):
    (tmp_path / "syntax.toml").write_text("[materials.jelly\n")
    (tmp_path / "nu.toml").write_text(
        "[materials.jelly]\ndensity = 1000\nyoungs_modulus = 1e6\npoisson_ratio = 0.5\n")
    (tmp_path / "contact.toml").write_text(
        "[[contacts]]\nbetween = ['steel', 'stele']\nsliding_friction = 0.3\n")
    return tmp_path


@pytest.mark.parametrize(("argv", "expected"), BAD_INPUTS.values(), ids=BAD_INPUTS.keys())
def test_bad_input_gives_one_error_line_and_exit_code_2(capsys, bad_files, argv, expected):
    argv = [a.replace("{tmp}", str(bad_files)) for a in argv]
    err = run_error(capsys, argv)
    assert expected in err


@pytest.mark.parametrize("module", ["hsgran", "hsgran.cli"])
def test_command_exits_2_without_traceback(module):
    proc = subprocess.run(
        [sys.executable, "-m", module, *_replace(_OK, "--radius", "nan")],
        capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == EXIT_BAD_INPUT
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    assert proc.stderr == "hsgran: error: --radius: must be a finite number > 0, got 'nan'\n"
