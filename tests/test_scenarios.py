"""Scenario files: every shipped one loads; bad input is refused with file, key and why."""

from __future__ import annotations

from pathlib import Path

import pytest

from modbus_bridge.scenario import ScenarioError, load_scenario, resolve_scenario, shipped_scenarios

FIXTURES = Path(__file__).parent / "harness_fixtures"
GOOD = (FIXTURES / "small_fopdt.toml").read_text(encoding="utf-8")


def test_shipped_scenarios_load():
    paths = shipped_scenarios()
    assert paths, "no shipped scenarios"
    for p in paths:
        sc = load_scenario(p)
        assert sc.name == p.stem
        assert sc.zones and all(z.phases for z in sc.zones)
        sc.build_plant()


def test_default_scenario_is_seed003():
    sc = load_scenario(resolve_scenario(None))
    assert sc.plant_model == "fopdt"
    assert (sc.plant_params["time_constant_s"], sc.plant_params["dead_time_s"]) == (23.4, 10.6)


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "bad.toml"
    p.write_text(text, encoding="utf-8")
    return p


BAD_CASES = [
    # (replace old, by new, expected key in message, expected reason fragment)
    ('name = "small fopdt"', 'name = "small fopdt"\ncolour = "red"', "colour", "unknown key"),
    (
        "description = \"test scenario: FOPDT, instant 'tuning', step, load step\"\n",
        "",
        "description",
        "missing required field",
    ),
    ("dt_s = 0.1", "dt_s = 0.0", "dt_s", "must be > 0"),
    ("time_constant_s = 20.0", "time_constant_s = -3.0", "plant.time_constant_s", ">= 0"),
    ("time_constant_s = 20.0", "time_constant_z = 20.0", "plant.time_constant_z", "unknown key"),
    ('model = "fopdt"', 'model = "warp_drive"', "plant.model", "must be one of"),
    ("gain_c_per_pct = 1.0\n", "", "plant.gain_c_per_pct", "missing required field"),
    ("noise_sigma_c = 0.05", "noise_sigma_c = -1.0", "zone[1].sensor.noise_sigma_c", ">= 0"),
    ('name = "z1"\nplc_zone = 1', 'name = "z1"\nplc_zone = 1\nchannel = 3', "zone[1].channel", "1 channel"),
    ("duration_s = 40.0", 'duration_s = 40.0\nuntil = "tuned"', "zone[1].phase[2].duration_s", "exactly one"),
    ("duration_s = 40.0", "end_at_s = 0.0", "zone[1].phase[2].end_at_s", "must be > 0"),
    ("timeout_s = 60.0\n", "", "zone[1].phase[1].timeout_s", "needs a timeout"),
    ("at_s = 2.0", "at_s = 50.0", "zone[1].phase[3].disturbance[1].at_s", "after the end of its phase"),
    ('kind = "load_step"', 'kind = "meteor"', "zone[1].phase[3].disturbance[1].kind", "must be one of"),
    ("delta_pct = 5.0", "delta_pc = 5.0", "zone[1].phase[3].disturbance[1].delta_pc", "unknown key"),
    ('mode = "TUNE"', 'mode = "TURBO"', "zone[1].phase[1].mode", "must be one of"),
    ("setpoint_c = 70.0", "setpoint_c = nan", "zone[1].phase[2].setpoint_c", "finite"),
    ("setpoint_c = 70.0", 'setpoint_c = "hot"', "zone[1].phase[2].setpoint_c", "must be float"),
    ("seed = 7", "seed = -1", "seed", ">= 0"),
    ("dead_time_s = 1.0", "dead_time_s = 1.0\ntime_constant_scale = 0.0", "plant.time_constant_scale", "> 0"),
    ("dead_time_s = 1.0", "dead_time_s = 1.0\nu_min_pct = 5.0\nu_max_pct = 1.0", "plant", "impossible"),
]


@pytest.mark.parametrize(("old", "new", "key", "why"), BAD_CASES)
def test_bad_input_names_file_key_and_reason(tmp_path, old, new, key, why):
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert str(path) in msg and key in msg and why in msg, msg


def test_not_toml_and_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_scenario(write(tmp_path, "name = = 3"))
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(ScenarioError, match="shipped"):
        resolve_scenario("no_such_scenario_name")


def test_raw_path_needs_an_adc(tmp_path):
    text = GOOD + '\n[plc]\npv_path = "raw"\n'
    with pytest.raises(ScenarioError, match="sensor.adc"):
        load_scenario(write(tmp_path, text))
