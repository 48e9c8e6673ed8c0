"""Zones on one body, through Modbus on the TCLab (two heaters on one board): a zone whose step test ran
while the other zone changed its heat carries alarm bit 23 (tune_shared) from the end of its test on;
zones tuned one after the other, as t4_tclab does, carry none."""

from __future__ import annotations

import dataclasses

import numpy as np

from modbus_bridge.scenario import Variant, load_scenario, resolve_scenario

from .conftest import run_scenario

TUNE_SHARED_BIT = 1 << 23
SHORT_HOLD_S = 20.0


def tclab(sc, zone1_phases, zone2_phases):
    z1, z2 = sc.zones
    return dataclasses.replace(sc, zones=[dataclasses.replace(z1, phases=zone1_phases),
                                          dataclasses.replace(z2, phases=zone2_phases)],
                               variants=[Variant("PID")])


def test_zones_tuned_together_flag_their_models(harness):
    sc = load_scenario(resolve_scenario("t4_tclab"))
    tune1, hold1, _ = sc.zones[0].phases
    configure, _, tune2, hold2 = sc.zones[1].phases
    tune2_together = dataclasses.replace(tune2, writes={**configure.writes, **tune2.writes},
                                         setpoint_c=tune1.setpoint_c)
    short = {"duration_s": SHORT_HOLD_S}
    ((result, _),) = run_scenario(harness, tclab(sc, [tune1, dataclasses.replace(hold1, **short)],
                                                 [tune2_together, dataclasses.replace(hold2, **short)]))
    assert result.error is None, result.error
    for tr in result.zones:
        assert tr.phases[0].outcome == "ok", f"{tr.name}: {tr.phases[0].outcome}"
        t, alarm, u = np.asarray(tr.t), np.asarray(tr.alarm), np.asarray(tr.u)
        t_end = tr.phases[1].t_start
        flagged = (alarm & TUNE_SHARED_BIT) != 0
        assert not np.any(flagged[t < t_end - 1.0]), f"{tr.name}: flagged before its model was published"
        assert np.all(flagged[t >= t_end]), f"{tr.name}: tuned beside the other zone's step test, not flagged"
        assert np.all(u[t >= t_end] > 0.0), f"{tr.name}: a warning, yet the loop stopped holding"


def test_zones_tuned_one_after_the_other_are_not_flagged(harness):
    sc = load_scenario(resolve_scenario("t4_tclab"))
    tune1, hold1, _ = sc.zones[0].phases
    configure, wait, tune2, hold2 = sc.zones[1].phases
    short = {"duration_s": SHORT_HOLD_S}  # zone 1 holds on while zone 2 waits and tunes
    zone1 = [tune1, dataclasses.replace(hold1, **short)]
    zone2 = [configure, wait, tune2, dataclasses.replace(hold2, **short)]
    ((result, _),) = run_scenario(harness, tclab(sc, zone1, zone2))
    assert result.error is None, result.error
    for tr in result.zones:
        assert [ph.outcome for ph in tr.phases if ph.name == "tune"] == ["ok"], tr.name
        assert not np.any(np.asarray(tr.alarm) & TUNE_SHARED_BIT), f"{tr.name}: flagged, yet tuned alone"
