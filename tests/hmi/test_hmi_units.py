"""The panel's parts without a browser: access levels, store retention, alarm texts, metadata checks,
the Modbus poller against the soft-PLC (block reads, write read-back, refusals, audit), simulate's plant."""

from __future__ import annotations

import asyncio
import math
import time

import pytest

from hmi.auth import ENGINEER, OPERATOR, Access, AccessConfigError, hash_password, verify_password
from hmi.model import Meta, load_model
from hmi.store import Retention, Store
from modbus_bridge.alarm_texts import alarm_texts, describe_bits, error_texts
from modbus_bridge.regmap import load_register_map


def test_passwords_are_kept_hashed(tmp_path) -> None:
    h = hash_password("s3cret")
    assert h.startswith("scrypt$") and "s3cret" not in h
    assert verify_password("s3cret", h) and not verify_password("wrong", h)
    assert not verify_password("s3cret", "garbage")
    access = Access.load(tmp_path, env={"THERMOST_HMI_ENGINEER_PASSWORD": "pw"})
    assert "pw" not in access.hashes[ENGINEER]
    assert access.login(ENGINEER, "pw") is None
    assert access.login(ENGINEER, "nope") == "wrong password"
    assert access.login(OPERATOR, "") is None  # no operator password configured
    off = Access.load(tmp_path, env={})
    assert "engineer level is off" in off.login(ENGINEER, "anything")


def test_access_config_file(tmp_path) -> None:
    (tmp_path / "hmi-access.toml").write_text(f'engineer = "{hash_password("cfg")}"\n')
    assert Access.load(tmp_path, env={}).login(ENGINEER, "cfg") is None
    (tmp_path / "hmi-access.toml").write_text('engineer = "plain text"\n')
    with pytest.raises(AccessConfigError, match="hash"):
        Access.load(tmp_path, env={})


def test_store_keeps_history_and_prunes_by_age_and_rows(tmp_path) -> None:
    store = Store(tmp_path, Retention(samples_s=100.0, events_s=1000.0, max_rows=5))
    now = time.time()
    store.add_samples([(now - 200 + k, 1, 20.0 + k, 30.0, 5.0, 2, 0, 1.0, 2.0, 3.0) for k in range(3)])
    store.add_samples([(now - 10 + k, 1, 25.0, 30.0, 5.0, 2, 0, 1.0, 2.0, 3.0) for k in range(8)])
    store.add_audit("engineer", "fKpZone1", 3.7, 2.0, "accepted", "")
    assert len(store.samples(1, now - 300)) == 11
    removed = store.prune(now, every_s=0)
    assert removed >= 6
    left = store.samples(1, now - 300)
    assert len(left) == 5 and all(t >= now - 100 for t, *_ in left)
    assert store.audit()[0][2] == "fKpZone1"
    store.save_tune(1, now, {"fKpZone1": 3.7}, "")
    store.close()
    reopened = Store(tmp_path)  # history and the gains before TUNE survive a restart
    assert len(reopened.samples(1, now - 300)) == 5
    assert reopened.load_tune(1) == (now, {"fKpZone1": 3.7}, "") and reopened.load_tune(2) is None


def test_alarm_and_error_texts_come_from_the_library_reference() -> None:
    texts = alarm_texts()
    assert texts[0].startswith("sensor open") and texts[5].startswith("heater open circuit")
    assert texts[17].startswith("tuning error") and "fTempLowLow" in texts[9] and 22 in texts
    assert describe_bits(1 | 1 << 16, texts) == [(0, texts[0]), (16, texts[16])]
    assert "TUNE: timeout" in error_texts()[13]


def test_meta_check_refuses_bad_entries() -> None:
    m = Meta(unit="degC", min=0.0, max=300.0)
    assert m.check(150.0) is None
    assert "below the minimum 0" in m.check(-1.0)
    assert "above the maximum 300" in m.check(301.0)
    assert m.check(math.nan) == "not a finite number"
    assert "not one of" in Meta(enum={0: "IDLE", 2: "ACTIVE"}).check(1)


def test_model_finds_both_zones_and_reads_in_few_blocks() -> None:
    from modbus_bridge.client import plan_reads

    model = load_model(load_register_map())
    assert [z.number for z in model.zones] == [1, 2]
    spans = plan_reads([model.regmap[n] for n in model.fast_tags()])
    assert len(spans) <= 8, [(s.table, s.start, s.count) for s in spans]


def test_tuning_and_fuzzy_robustness_registers_reach_the_panel() -> None:
    """The registers TUNE's noise-sized filter and the fuzzy adapter's Ms bound added: roles for the pages
    that show them, and the parameters among the page's groups (a coil included), in every zone."""
    model = load_model(load_register_map())
    roles = ("noise_pp", "t_filter", "t_filter_used", "fz_ms_reachable", "fz_ms_max", "fz_gain_scale",
             "fz_box_share", "fz_symmetric", "fz_sign_band")
    for z in model.zones:
        n = z.number
        assert all(z.has(r) for r in roles), [r for r in roles if not z.has(r)]
        assert (z["noise_pp"], z["t_filter"], z["fz_ms_reachable"]) == (
            f"fTuneNoisePpZone{n}", f"fTFilterTunedZone{n}", f"fFuzzyMsReachableZone{n}")
        groups = model.parameter_groups(n)
        fuzzy = {f"fFuzzyMsMaxZone{n}", f"fFuzzySignBandZone{n}", f"bFuzzySymmetricZone{n}"}
        assert fuzzy <= set(groups["fuzzy"])
        assert f"fTuneFilterLagShareZone{n}" in groups["tuning"]
        shown = {name for names in groups.values() for name in names}
        # results the PLC writes are shown on their pages, not offered as parameters
        assert not {f"fFuzzyMsReachableZone{n}", f"fTFilterUsedZone{n}", f"fTuneNoisePpZone{n}"} & shown


def test_the_robustness_text_says_why_no_ms_is_shown(monkeypatch) -> None:
    """fFuzzyMsReachable reads 0 with the bound off, and without a model or while the box is searched."""
    from types import SimpleNamespace

    import hmi.pages_more as pages

    z = load_model(load_register_map()).zones[0]
    values = {z["fz_ms_reachable"]: 0.0, z["fz_ms_max"]: 2.0}
    monkeypatch.setattr(pages, "panel", lambda: SimpleNamespace(value=values.get))
    assert "being searched" in pages._robustness_text(z)
    values[z["fz_ms_max"]] = 1.0
    assert "Ms bound off" in pages._robustness_text(z)


async def polled_until(predicate, tries: int = 50) -> None:
    """Give the poller up to tries tenths of a second to make predicate true."""
    for _ in range(tries):
        await asyncio.sleep(0.1)
        if predicate():
            return


def test_poller_reads_writes_and_audits_against_the_soft_plc(tmp_path) -> None:
    from hmi.poller import Poller
    from plc.bundle import bundle_text
    from plc.runtime.server import SoftPlc

    async def scenario() -> None:
        model = load_model(load_register_map())
        store = Store(tmp_path)
        async with SoftPlc(bundle_text(), port=0) as plc:
            poller = Poller(model, "127.0.0.1", plc.port, rate_hz=10, store=store)
            pushed: list[int] = []

            def broken() -> None:
                raise RuntimeError("page gone")

            poller.listeners |= {lambda: pushed.append(poller.seq), broken}
            poller.start()
            try:  # a failed check stops the poller too, or its task outlives the PLC
                await polled_until(lambda: len(poller.samples) >= 5 and poller.diag.scan_count)
                assert poller.diag.connected and not poller.stale
                assert len(pushed) >= 5 and broken not in poller.listeners  # a failing page is dropped
                assert poller.diag.requests_per_cycle <= 8
                ok = await poller.write({"fSetpointZone1": 55.0}, "operator")
                assert ok.ok, ok.message
                refused = await poller.write({"fYMinZone1": 100.0}, "engineer")  # fYMin must stay < fYMax
                assert not refused.ok and "refused by the PLC" in refused.message
                bad = await poller.write({"nModeZone1": 1e9}, "operator")
                assert not bad.ok and "not written" in bad.message
                busy = await asyncio.gather(poller.write({"fSetpointZone1": 60.0}, "operator"),
                                            poller.write({"fSetpointZone1": 61.0}, "operator"))
                assert sorted(r.ok for r in busy) == [False, True]  # a double click writes once
            finally:
                await poller.stop()
        results = [row[5] for row in store.audit()]
        assert results.count("accepted") == 2 and "refused" in results and "failed" in results
        store.close()

    asyncio.run(scenario())


def test_a_write_during_an_alarm_reaction_is_not_called_refused_by_a_latched_refusal(tmp_path) -> None:
    """Alarm bit 16 still latched from a refused write, the zone in ERROR from an alarm reaction (error 20,
    not a parameter error): a valid write is accepted, and a refused one is still caught by its read-back."""
    from hmi.poller import Poller
    from plc.bundle import bundle_text
    from plc.runtime.server import SoftPlc

    async def scenario() -> None:
        model = load_model(load_register_map())
        async with SoftPlc(bundle_text(), port=0) as plc:
            poller = Poller(model, "127.0.0.1", plc.port, rate_hz=10)
            poller.start()
            await polled_until(lambda: poller.diag.scan_count)
            assert not (await poller.write({"fYMinZone1": 100.0}, "engineer")).ok  # latches bit 16
            await poller.write({"fPvZone1": 999.0, "nModeZone1": 2}, "engineer", verify=False)  # sensor open
            await polled_until(lambda: poller.values.get("nErrorIdZone1") == 20)
            assert poller.values.get("nErrorIdZone1") == 20
            ok = await poller.write({"fSetpointZone1": 55.0}, "operator")
            assert ok.ok, ok.message
            refused = await poller.write({"fYMinZone1": 100.0}, "engineer")
            assert not refused.ok and "the PLC keeps fYMinZone1" in refused.message
            await poller.stop()

    asyncio.run(scenario())


def test_poller_reports_an_unreachable_plc(tmp_path) -> None:
    from hmi.poller import Poller

    async def scenario() -> None:
        poller = Poller(load_model(load_register_map()), "127.0.0.1", 1, rate_hz=10)
        poller.start()
        await asyncio.sleep(0.5)
        assert poller.stale and not poller.diag.connected and "cannot connect" in poller.diag.error
        result = await poller.write({"fSetpointZone1": 50.0}, "operator")
        assert not result.ok
        await poller.stop()

    asyncio.run(scenario())


def test_a_write_on_old_values_says_why_it_is_refused() -> None:
    """A panel whose values have aged (the PLC, the network or the panel itself stalled) refuses a write and
    says so; only a lost connection is called unreachable."""
    from hmi.poller import Poller

    poller = Poller(load_model(load_register_map()), "127.0.0.1", 1, rate_hz=10)
    assert poller.stale_reason() == "the PLC is not reachable"
    poller.diag.connected, poller.diag.last_ok = True, time.time()
    assert poller.stale_reason() == "" and not poller.stale
    poller.diag.last_ok = time.time() - 5.0
    assert poller.stale and poller.stale_reason().startswith("no fresh values from the PLC for 5.")


def test_simulate_plant_commands() -> None:
    from modbus_bridge.scenario import load_scenario, resolve_scenario
    from modbus_bridge.simulate import PlantSim

    sim = PlantSim(load_scenario(resolve_scenario("t4_tclab")), load_register_map())
    assert [z.plc_zone for z in sim.zones] == [1, 2]
    assert sim.configuration()["fYMinZone2"] == 0.0  # zone 2's first-phase writes
    writes = sim.measure(0.5)
    assert set(writes) == {"fPvZone1", "fPvZone2", "nPvSeqZone1", "nPvSeqZone2"}
    assert sim.measure(0.5)["nPvSeqZone1"] == writes["nPvSeqZone1"] + 1  # heartbeat with every new PV
    assert "sensor: open" in sim.command("fault 1 open")
    assert sim.measure(0.5)["fPvZone1"] != pytest.approx(writes["fPvZone1"], abs=5)
    assert "load: 5" in sim.command("load 2 5")
    for bad in ("fault 9 open", "fault 1 melted", "load 1 nan", "heater 1 maybe", "bogus", "load 1"):
        assert sim.command(bad).startswith("error:"), bad
    sim.apply({"fYZone1": 100.0, "fYZone2": math.nan}, 0.5)
    assert sim.zones[1].u == 0.0


def test_simulate_cli_refuses_bad_input() -> None:
    from plc.cli import main

    assert main(["simulate", "--speed", "3"]) == 2  # 100 ms is not a multiple of 3
    assert main(["simulate", "--speed", "0"]) == 2
    assert main(["simulate", "nope"]) == 2
    assert main(["simulate", "--plc", "host-without-port"]) == 2
    assert main(["hmi", "--plc", "x"]) == 2
    assert main(["hmi", "--rate", "nan"]) == 2
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert main(["hmi", "--port", str(port), "--plc", "127.0.0.1:1"]) == 2  # address in use
        assert main(["simulate", "--port", str(port)]) == 2


def test_simulate_plant_writes_pv_over_modbus_to_a_plc(tmp_path) -> None:
    """The plant side alone (as with --plc HOST:PORT) against a real-time soft-PLC at 10 x."""
    from modbus_bridge.client import PlcClient
    from modbus_bridge.scenario import load_scenario, resolve_scenario
    from modbus_bridge.simulate import PlantSim, Simulation
    from plc.bundle import bundle_text, with_speed
    from plc.runtime.server import SoftPlc

    async def scenario() -> None:
        rm = load_register_map()
        async with SoftPlc(with_speed(bundle_text(), 10), port=0) as plc:
            sim = PlantSim(load_scenario(resolve_scenario("seed003_hotend_fuzzy")), rm)
            runner = Simulation(sim, "127.0.0.1", plc.port, 10.0, log=lambda _s: None)
            stop = asyncio.Event()
            task = asyncio.create_task(runner.run(stop))
            async with PlcClient("127.0.0.1", plc.port, rm) as c:
                await asyncio.sleep(0.5)
                await c.write_tags({"nModeZone1": 4, "fYManualZone1": 50.0})  # MANUAL 50 %
                await asyncio.sleep(2.5)  # 25 s of plant time: past the 10.6 s dead time
                v = await c.read_tags(["fPvZone1", "fYZone1"])
            stop.set()
            await task
        assert runner.steps > 100 and runner.connected
        assert v["fYZone1"] == pytest.approx(50.0)
        assert v["fPvZone1"] > 162.0  # the plant (160 degC at rest) heats with the PLC's output

    asyncio.run(scenario())


@pytest.mark.parametrize("catch_up_s", [None, 0.02], ids=["wall_clock", "slips"])
def test_a_stalled_plant_makes_up_at_most_what_it_is_allowed(catch_up_s) -> None:
    """After a 0.4 s stall of its process the plant makes up the missed time (up to CATCH_UP_S), or, beside
    the embedded soft-PLC (0.02 s here: two of its scans at 10 x), slips as the PLC's scheduler does."""
    from modbus_bridge.scenario import load_scenario, resolve_scenario
    from modbus_bridge.simulate import CATCH_UP_S, PlantSim, Simulation
    from plc.bundle import bundle_text, with_speed
    from plc.runtime.server import SoftPlc

    speed, stall_s, step_s = 10, 0.4, 0.1  # seed 003's plant step

    async def scenario() -> tuple[float, float]:
        rm = load_register_map()
        async with SoftPlc(with_speed(bundle_text(), speed), port=0) as plc:
            sim = PlantSim(load_scenario(resolve_scenario("seed003_hotend_fuzzy")), rm)
            runner = Simulation(sim, "127.0.0.1", plc.port, float(speed), log=lambda _s: None,
                                catch_up_s=CATCH_UP_S if catch_up_s is None else catch_up_s)
            stop = asyncio.Event()
            task = asyncio.create_task(runner.run(stop))
            await asyncio.sleep(0.5)
            t0, wall0 = sim.t, time.perf_counter()
            time.sleep(stall_s)  # the whole process stalls: plant, soft-PLC and their loop
            await asyncio.sleep(0.3)
            advance, wall = sim.t - t0, time.perf_counter() - wall0
            stop.set()
            await task
            return advance, wall

    advance, wall = asyncio.run(scenario())
    unstalled = (wall - stall_s) * speed  # plant time of the wall time the loop ran
    if catch_up_s is None:
        assert advance >= unstalled + 0.5 * stall_s * speed, (advance, wall)
    else:
        assert advance <= unstalled + 3 * step_s, (advance, wall)
