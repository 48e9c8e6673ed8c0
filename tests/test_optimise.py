"""`thermost optimise` and the executor: reproducible with a seed, better than its start, one clear line
for bad input; the same experiments give the same traces locally, serially and on a local Dask cluster."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from modbus_bridge.optimise.executor import DaskExecutor, LocalExecutor, SerialExecutor
from modbus_bridge.optimise.experiment import Outcome, PidGains, cost, max_overshoot, run_experiment
from modbus_bridge.optimise.search import Optimiser, Settings, seed004_simplex
from modbus_bridge.scenario import load_scenario
from plc.cli import main

FIXTURE = Path(__file__).resolve().parent / "harness_fixtures" / "small_fopdt.toml"


def test_cli_cost_choices_are_the_costs():
    from modbus_bridge.optimise.cli import COST_CHOICES
    from modbus_bridge.optimise.experiment import COSTS

    assert COST_CHOICES == COSTS


@pytest.mark.parametrize(
    ("values", "expected"),
    [({"overshoot_pct": 4.3, "true_overshoot_pct": 0.1}, 0.1), ({"overshoot_pct": 4.3}, 4.3)],
    ids=["true-temperature", "pv-only"],
)
def test_the_overshoot_constraint_reads_the_true_temperature_where_recorded(values, expected):
    """A noisy PV adds its peaks to the overshoot: the constraint judges the process, as the scorecard."""
    from modbus_bridge.analysis import PhaseMetrics

    step = PhaseMetrics("z", "step", "step", 0.0, 10.0, "ok", values=dict(values))
    empty = np.zeros(0)
    o = Outcome("x", [step], empty, empty, empty, empty, empty, [("step", 0.0, 10.0)])
    assert max_overshoot(o) == pytest.approx(expected)


def test_seed004_simplex_is_regular():
    x = seed004_simplex(np.zeros(3), 1.0)
    d = [np.linalg.norm(x[i] - x[j]) for i in range(4) for j in range(i + 1, 4)]
    assert np.allclose(d, 1.0)  # every edge has the length delta (seed 004 eq. 11-13)


SHORT = """
name = "short fopdt"
description = "no tuning: a step from rest and a load, 30 s of plant time per experiment"
seed = 2
[plant]
model = "fopdt"
gain_c_per_pct = 1.0
time_constant_s = 20.0
dead_time_s = 1.0
ambient_c = 25.0
[[zone]]
name = "z1"
plc_zone = 1
[zone.sensor]
noise_sigma_c = 0.05
[[zone.phase]]
name = "step"
mode = "ACTIVE"
setpoint_c = 35.0
duration_s = 20.0
[[zone.phase]]
name = "load"
duration_s = 10.0
[[zone.phase.disturbance]]
kind = "load_step"
delta_pct = 5.0
"""


def test_optimise_is_reproducible_and_improves_on_its_start(tmp_path, capsys):
    scen = tmp_path / "short.toml"
    scen.write_text(SHORT, encoding="utf-8")
    outs = []
    for name in ("a.json", "b.json"):
        out = tmp_path / name
        args = ["optimise", str(scen), "--evals", "8", "--seed", "11", "--workers", "2", "--quiet"]
        assert main([*args, "-o", str(out)]) == 0
        outs.append(json.loads(out.read_text()))
    a, b = outs
    assert a["parameters"] == b["parameters"] and a["cost_value"] == b["cost_value"]
    assert a["seed"] == 11 and a["evaluations"] >= 8
    assert a["objective"] <= a["start"]["objective"]  # the start is one of the experiments
    assert set(a["registers"]) == {"fKpZone1", "fTnZone1", "fTvZone1", "fTdZone1"}
    assert a["registers"]["fKpZone1"] == a["parameters"]["kp_pct_per_c"] > 0
    assert "short fopdt: Kp" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "why"),
    [
        (["--evals", "0"], "--evals"),
        (["--max-ms", "0.9"], "--max-ms"),
        (["--max-overshoot", "nan"], "--max-overshoot"),
        (["--plc", "nohost"], "HOST:PORT"),
        (["--plc", "127.0.0.1:1", "--scheduler", "127.0.0.1:1"], "exclude"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(args, why, capsys):
    assert main(["optimise", str(FIXTURE), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and why in err


def test_bad_scenario_and_unreachable_scheduler(tmp_path, capsys):
    assert main(["optimise", str(tmp_path / "none.toml")]) == 2
    assert "no such scenario" in capsys.readouterr().err
    pytest.importorskip("distributed", reason="the Dask client is an optional dependency (thermost[dask])")
    assert main(["optimise", str(FIXTURE), "--scheduler", "tcp://127.0.0.1:9", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no Dask scheduler" in err


def _experiments():
    sc = load_scenario(FIXTURE)
    opt = Optimiser(sc, Settings(evals=2, settle_s=30.0), SerialExecutor())
    return opt, [opt.experiment(PidGains(kp, 20.0, 1.0)) for kp in (2.0, 6.0)]


def test_local_serial_and_dask_executors_give_the_same_experiments():
    distributed = pytest.importorskip(
        "distributed", reason="the Dask executor needs 'distributed' (pip install 'thermost[dask]')"
    )
    opt, exps = _experiments()
    with SerialExecutor() as ex:
        serial = ex.map(run_experiment, exps)
    with LocalExecutor(2) as ex:
        local = ex.map(run_experiment, exps)
    with distributed.LocalCluster(
        host="127.0.0.1",
        protocol="tcp",
        n_workers=1,
        threads_per_worker=2,
        processes=False,
        dashboard_address=None,
    ) as cluster:
        done: list[int] = []
        with DaskExecutor(cluster.scheduler_address) as ex:
            assert ex.workers == 2
            remote = ex.map(run_experiment, exps, progress=lambda n, total: done.append(n))
    assert done[-1] == 2
    for s, lo, re in zip(serial, local, remote, strict=True):
        assert s.error is None and np.array_equal(s.pv, lo.pv) and np.array_equal(s.pv, re.pv)
    assert all(0.0 < cost(o, "iae") < float("inf") for o in serial)
    # a larger Kp: a smaller robustness margin
    assert opt.model.ms(PidGains(6.0, 20.0, 1.0)) > opt.model.ms(PidGains(2.0, 20.0, 1.0))
