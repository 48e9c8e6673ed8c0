"""Loop closer end to end against the embedded soft-PLC, with a tiny fixture program
(tests/harness_fixtures/p_harness_test.st) so these tests do not depend on the controller library."""

from __future__ import annotations

import asyncio
import dataclasses
import socket
from pathlib import Path

import pytest

from modbus_bridge.binding import ControllerCodes, resolve_zone
from modbus_bridge.client import PlcClient, PlcError
from modbus_bridge.loop import close_loop
from modbus_bridge.preflight import check_bindings
from modbus_bridge.regmap import RegisterMapError, load_register_map
from modbus_bridge.runner import HarnessSetup, run_variants
from modbus_bridge.scenario import Variant, load_scenario

FIXTURES = Path(__file__).parent / "harness_fixtures"
PROGRAM = (FIXTURES / "p_harness_test.st").read_text(encoding="utf-8")
SCENARIO = FIXTURES / "small_fopdt.toml"

server = pytest.importorskip("plc.runtime.server", reason="the soft-PLC runtime is needed")


def setup() -> HarnessSetup:
    regmap = load_register_map(sources=[("p_harness_test.st", PROGRAM)])
    return HarnessSetup(regmap=regmap, codes=ControllerCodes.load(), program=PROGRAM)


def run(scenario, **kw):
    return asyncio.run(run_variants(scenario, setup(), **kw))


def test_closed_loop_runs_phases_and_is_deterministic():
    sc = load_scenario(SCENARIO)
    ((r1, m1),) = run(sc)
    ((r2, _),) = run(sc)
    assert r1.error is None
    tr = r1.zones[0]
    assert [p.name for p in tr.phases] == ["tune", "step", "load"]
    tune = tr.phases[0]
    # the fixture reports TUNED after 100 scans: the phase ends on that event, not on a timer
    assert tune.outcome == "ok" and 10.0 <= tune.t_end - tune.t_start <= 10.5
    assert tr.phases[2].disturbances and tr.phases[2].disturbances[0][1] == "load_step"
    assert r1.plant_time_s == pytest.approx(tr.phases[-1].t_end)
    # stepped mode is deterministic bit for bit (same seed -> same noise, same PLC arithmetic)
    assert r1.zones[0].pv == r2.zones[0].pv and r1.zones[0].u == r2.zones[0].u
    step = next(pm for pm in m1 if pm.phase == "step")
    assert step.kind == "step" and step.values["rise_time_s"] > 0
    load = next(pm for pm in m1 if pm.phase == "load")
    assert load.kind == "disturbance" and "recovery_time_2pct_s" in load.values
    # the PI fixture compensates the 5 % load: its output ends about 5 % higher than before the load
    u_before = [
        u for u, t in zip(tr.u, tr.t, strict=True) if tr.phases[1].t_end - 5.0 <= t < tr.phases[1].t_end
    ]
    u_after = [u for u, t in zip(tr.u, tr.t, strict=True) if t >= tr.phases[2].t_end - 5.0]
    assert sum(u_after) / len(u_after) - sum(u_before) / len(u_before) == pytest.approx(5.0, abs=1.5)


def test_pwm_output_path_averages_coils():
    sc = load_scenario(SCENARIO)
    sc = dataclasses.replace(sc, output_path="pwm")
    ((r, m),) = run(sc)
    assert r.error is None
    tr = r.zones[0]
    assert set(tr.pwm) <= {0, 1} and 0 < sum(tr.pwm) < len(tr.pwm)
    # during the fixture's 50 % "tuning" output the PWM duty is 50 %
    tune_pwm = [p for p, ph in zip(tr.pwm, tr.phase, strict=True) if ph == "tune"]
    assert sum(tune_pwm) / len(tune_pwm) == pytest.approx(0.5, abs=0.02)
    assert any("pwm_switches_per_min" in pm.values for pm in m)


def test_raw_pv_path_writes_adc_counts():
    sc = load_scenario(SCENARIO)
    zone = sc.zones[0]
    adc = dataclasses.replace(zone.sensor.adc, kind="pt100", noise_lsb=0.0)  # the exact count
    sensor = dataclasses.replace(zone.sensor, adc=adc)
    sc = dataclasses.replace(sc, pv_path="raw", zones=[dataclasses.replace(zone, sensor=sensor)])

    async def go():
        s = setup()
        async with server.SoftPlc(PROGRAM, port=0, stepped=True) as soft:
            async with PlcClient("127.0.0.1", soft.port, s.regmap) as client:
                await close_loop(sc, Variant("raw"), client, s.bindings(sc), s.codes, max_plant_time_s=1.0)
                return await client.read("nPvRawZone1")

    counts = asyncio.run(go())
    assert counts == round(109.73 * 16)  # PT100 at 25 °C = 109.73 Ω, 1/16 Ω per count


def test_missing_tag_is_one_clear_line():
    sc = load_scenario(SCENARIO)
    text = PROGRAM.replace("nStateZone1", "nStatusZone1")
    regmap = load_register_map(sources=[("x.st", text)])
    with pytest.raises(RegisterMapError, match="zone 1: no register for role 'state'"):
        resolve_zone(regmap, 1)
    s = setup()
    bad = dataclasses.replace(
        sc.zones[0], phases=[dataclasses.replace(sc.zones[0].phases[0], writes={"fNoSuchTag": 1.0})]
    )
    with pytest.raises(RegisterMapError, match="fNoSuchTag"):
        check_bindings(dataclasses.replace(sc, zones=[bad]), s.bindings(sc), s.codes, s.regmap)


def test_a_plant_step_that_is_not_the_plc_time_of_its_scans_is_refused():
    """A stepped run whose plant step differs from scans_per_step x the controller's task cycle would
    identify every time constant off by their ratio; every shipped scenario matches."""
    s = HarnessSetup.default()  # the application, whose zones count fTaskCycleTimeZone<n> per scan
    shipped = sorted((Path(__file__).parents[1] / "modbus_bridge" / "scenarios").glob("*.toml"))
    assert len(shipped) > 10
    for path in shipped:
        sc = load_scenario(path)
        check_bindings(sc, s.bindings(sc), s.codes, s.regmap)
    sc = load_scenario(shipped[0])
    slow = dataclasses.replace(sc, dt_s=2 * sc.dt_s)
    with pytest.raises(RegisterMapError, match=rf"set \[plc\] scans_per_step = {2 * sc.scans_per_step}\b"):
        check_bindings(slow, s.bindings(slow), s.codes, s.regmap)
    check_bindings(slow, s.bindings(slow), s.codes, s.regmap, stepped=False)  # real time: the PLC's own clock


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_unreachable_plc_is_one_clear_line():
    sc = load_scenario(SCENARIO)
    with pytest.raises(PlcError, match="cannot connect to PLC at 127.0.0.1"):
        run(sc, plc=f"127.0.0.1:{free_port()}")


def test_plc_that_stops_answering_keeps_the_trace():
    sc = load_scenario(SCENARIO)

    async def go():
        s = setup()
        soft = server.SoftPlc(PROGRAM, port=0, stepped=True)
        async with soft:
            client = PlcClient("127.0.0.1", soft.port, s.regmap, timeout_s=0.3, retries=1)
            await client.connect()

            def progress(done: float, total: float) -> None:
                if done >= 5.0 and not stopped:
                    stopped.append(True)
                    asyncio.get_running_loop().create_task(soft.close())

            stopped: list[bool] = []
            result = await close_loop(sc, Variant("x"), client, s.bindings(sc), s.codes, progress=progress)
            client.close()
            return result

    result = asyncio.run(go())
    assert (
        result.error is not None and "stopped answering" in result.error or "cannot connect" in result.error
    )
    assert 5.0 <= result.plant_time_s < 20.0
    assert len(result.zones[0].t) == result.steps > 0


def test_several_plcs_at_once_match_separate_runs():
    from modbus_bridge.runner import FleetJob, run_fleet

    sc = load_scenario(SCENARIO)
    other = dataclasses.replace(sc, seed=sc.seed + 1)

    async def go():
        s = setup()
        async with (
            server.SoftPlc(PROGRAM, port=0, stepped=True) as a,
            server.SoftPlc(PROGRAM, port=0, stepped=True) as b,
        ):
            return await run_fleet(
                [FleetJob(sc, f"127.0.0.1:{a.port}"), FleetJob(other, f"127.0.0.1:{b.port}")], s
            )

    fleet = asyncio.run(go())
    assert [r.error for r in fleet] == [None, None]
    ((alone, _),) = run(sc)
    assert fleet[0].zones[0].pv == alone.zones[0].pv  # concurrency changes nothing in stepped mode
    assert fleet[1].zones[0].pv != alone.zones[0].pv  # another seed, another noise sequence


def test_realtime_mode_paces_the_plant_and_reports_jitter():
    sc = load_scenario(SCENARIO)

    async def go():
        s = setup()
        async with server.SoftPlc(PROGRAM, port=0, stepped=False) as soft:
            async with PlcClient("127.0.0.1", soft.port, s.regmap) as client:
                assert not await client.stepped()
                return await close_loop(
                    sc,
                    Variant("rt"),
                    client,
                    s.bindings(sc),
                    s.codes,
                    realtime=True,
                    speed=4.0,
                    max_plant_time_s=2.0,
                )

    import time

    t0 = time.perf_counter()
    result = asyncio.run(go())
    wall = time.perf_counter() - t0
    assert result.error is None and result.realtime
    assert result.steps == 20 and len(result.jitter_ms) == 20
    assert wall >= 2.0 / 4.0 - 0.05  # paced: 2 s of plant time at 4x take at least 0.5 s
    assert all(j >= -1.0 for j in result.jitter_ms)  # never early


def test_pwm_duty_is_averaged_over_a_multi_scan_step():
    sc = load_scenario(SCENARIO)
    sc = dataclasses.replace(sc, output_path="pwm", scans_per_step=10, dt_s=1.0)
    ((r, _),) = run(sc)
    assert r.error is None
    tr = r.zones[0]
    # the fixture's PWM has a 10-scan period; at its 50 % tuning output every 10-scan step averages 0.5
    tune_u = [u for u, ph in zip(tr.u, tr.phase, strict=True) if ph == "tune"][1:]
    assert tune_u and all(u == pytest.approx(50.0) for u in tune_u)


def test_model_mismatch_changes_the_plant_mid_run():
    from modbus_bridge.scenario import Disturbance

    sc = load_scenario(SCENARIO)
    step = sc.zones[0].phases[1]
    slow_step = dataclasses.replace(step, disturbances=[Disturbance("model_mismatch", 0.0, 3.0)])
    slow = dataclasses.replace(
        sc, zones=[dataclasses.replace(sc.zones[0], phases=[sc.zones[0].phases[0], slow_step])]
    )
    nominal = dataclasses.replace(
        sc, zones=[dataclasses.replace(sc.zones[0], phases=[sc.zones[0].phases[0], step])]
    )
    ((a, ma),) = run(nominal)
    ((b, mb),) = run(slow)
    t_step = a.zones[0].phases[1].t_start
    same = [
        x == y for x, y, t in zip(a.zones[0].pv, b.zones[0].pv, a.zones[0].t, strict=False) if t <= t_step
    ]
    assert all(same)  # identical until the mismatch is applied
    rise = {m.phase: m.values["rise_time_s"] for m in ma if m.kind == "step"}
    rise_slow = {m.phase: m.values["rise_time_s"] for m in mb if m.kind == "step"}
    assert rise_slow["step"] > 1.5 * rise["step"]  # a 3x slower plant rises much more slowly


RAW_SCENARIO = """
name = "raw path"
description = "both zones through the application's raw inputs"
[plc]
pv_path = "raw"
[plant]
model = "tclab"
[[zone]]
name = "ntc zone"
plc_zone = 1
channel = 0
[zone.sensor]
adc = "ntc"
bits = 15
noise_sigma_c = 0.1
[[zone.phase]]
name = "hold"
mode = "ACTIVE"
setpoint_c = 30.0
duration_s = 5.0
[[zone]]
name = "pt100 zone"
plc_zone = 2
channel = 1
[zone.sensor]
adc = "pt100"
bits = 15
ohm_at_zero = 18.52
ohm_per_count = 0.011352
noise_sigma_c = 0.1
[[zone.phase]]
name = "hold"
mode = "ACTIVE"
setpoint_c = 30.0
duration_s = 5.0
"""


def test_raw_path_through_the_application(tmp_path):
    """The application converts the harness's ADC counts (NTC divider, PT100 card) back to the same
    temperature the simulated sensor produced: both ends share the sensor parameters."""
    app = HarnessSetup.default()
    if not app.regmap.find(r"nPvRawModbusZone[12]"):
        pytest.skip("the application has no Modbus-writable raw inputs (nPvRawModbusZone<n>)")
    path = tmp_path / "raw.toml"
    path.write_text(RAW_SCENARIO, encoding="utf-8")
    sc = load_scenario(path)

    async def go():
        async with server.SoftPlc(app.program_text(), port=0, stepped=True) as soft:
            async with PlcClient("127.0.0.1", soft.port, app.regmap) as client:
                await client.step(2)
                result = await close_loop(sc, Variant("raw"), client, app.bindings(sc), app.codes)
                used = await client.read_tags(["fXUsedZone1", "fXUsedZone2", "nPvRawModbusZone1"])
                return result, used

    result, used = asyncio.run(go())
    assert result.error is None, result.error
    assert used["nPvRawModbusZone1"] > 0
    assert used["fXUsedZone1"] == pytest.approx(result.zones[0].pv[-1], abs=1e-3)
    # the simulated PT100 follows IEC 60751 (A = 3.9083e-3, B = -5.775e-7); the library converts with seed
    # 000's older coefficients (3.90802e-3, -5.80195e-7): 0.002 °C apart at 21 °C, a real calibration offset
    assert used["fXUsedZone2"] == pytest.approx(result.zones[1].pv[-1], abs=5e-3)
