"""TUNE and the sensor's noise: the noise it measures at rest (and a rest it refuses), how long the sensor
holds each reading, and the filters and gain limits it sizes from them so the noise does not drive the
heater (docs/library.md, FC_ApplyTuningRule)."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

import numpy as np
import pytest

from modbus_bridge.plants.response import max_sensitivity, pid_frequency_response
from tests.st_helpers import ScanDriver
from tests.test_lib_tuner import (
    AMIGO_LOAD_GAIN_MIN,
    MODE_ACTIVE,
    RULE_AMIGO,
    RULE_AUTO,
    RULE_CHR,
    RULE_SIMC,
    SIMC_TN_FACTOR,
    SIMC_WEIGHT_0,
    TS,
    TUNE_READY,
    Fopdt,
    error_of,
    identified,
    rule_values,
    run_tune,
    setpoint_weight,
    simc_load_ratio,
    simc_tn,
    tuner_driver,
)


@pytest.fixture()
def uut() -> ScanDriver:
    return tuner_driver()


def filter_time(gain: float, noise_pp: float, goal_pp: float, hold: float, tu: float, share: float) -> float:
    """docs/library.md: the actual-value filter TUNE sizes so that the set's gain on noise (Kp, or 2 Kp for
    AUTO's sets with D) times the filtered noise meets the output goal, for noise that holds each value
    `hold` s (the PV's update interval)."""
    if gain * noise_pp <= goal_pp:
        return 0.0
    r = goal_pp / (gain * noise_pp)
    a = 2 * r * r / (1 + r * r)
    return min(hold * (1 - a) / a, share * tu)


def filtered_noise(noise_pp: float, tf: float, hold: float) -> float:
    """docs/library.md: noise held `hold` s, peak-to-peak, after the first-order actual-value filter (std
    ratio sqrt(aH / (2 - aH)), aH = H / (Tf + H))."""
    a = hold / (tf + hold)
    return noise_pp * math.sqrt(a / (2.0 - a))


@pytest.mark.parametrize(("noise", "share"), [(0.5, 0.1), (0.5, 0.02), (0.05, 0.1)],
                         ids=["sized", "at-the-lag-bound", "not-needed"])
def test_tune_sizes_the_actual_value_filter_from_the_measured_noise(uut, noise, share) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0, noise=noise, rng=random.Random(3))
    # the filter is sized for the rule's Kp; fTuneMsMax off keeps that Kp in the set (the detuning after it
    # is the auto-rule test's), and so does the noise limit off (its own bound is the noise-limited test's)
    run_tune(uut, plant, w=80.0, extra={"fTuneFilterLagShare": share, "fTuneMsMax": 0.0,
                                        "fTuneNoiseKpOutput": 0.0})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    got = identified(uut)
    noise_pp = uut.get("fbUut.fbTuner.fNoise")
    tf = uut.get("sPar.fTFilterTuned")
    assert uut.get("fbUut.fTuneNoiseInterval") == pytest.approx(TS, rel=1e-6)  # a new reading every cycle
    want = filter_time(got["fKp"], noise_pp, 2.0, TS, got["fTu"], share)
    assert tf == pytest.approx(want, rel=1e-3, abs=1e-6)
    if noise > 0.1:
        assert tf > 0.0
    if share < 0.1:
        assert tf == pytest.approx(share * got["fTu"], rel=1e-3)
    # the tuned filter runs from the tuned set on, and the published Ms includes its lag
    uut.set("fbUut.fX", plant.measure())
    uut.scan()
    assert uut.get("fbUut.fTFilterUsed") == pytest.approx(tf, abs=1e-6)
    w = np.logspace(-6, 3, 200_000)
    loop = (pid_frequency_response(got["fKp"], got["fTn"], got["fTv"], got["fTd"], w)
            * got["fKs"] * np.exp(-1j * w * got["fTu"]) / (1j * w * got["fTg"] + 1.0) / (1j * w * tf + 1.0))
    assert got["fMsTuned"] == pytest.approx(max_sensitivity(loop), rel=0.02)


@dataclass
class HeldSensor:
    """A plant read through a sensor that updates every `every` control cycles (an input card, a PV
    written over Modbus at the plant's pace): each noisy reading is held that long."""

    plant: Fopdt
    every: int
    calls: int = 0
    value: float = 0.0

    def measure(self) -> float:
        if self.calls % self.every == 0:
            self.value = self.plant.measure()
        self.calls += 1
        return self.value

    def step(self, u: float) -> None:
        self.plant.step(u)


@pytest.mark.parametrize("every", [2, 5, 10])
def test_tune_publishes_how_long_the_sensor_holds_each_reading(uut, every: int) -> None:
    """The noise's update interval TUNE measures at rest: the cycles per change of X, times the cycle."""
    run_tune(uut, HeldSensor(Fopdt(k=0.9, t=100.0, l=10.0, noise=0.5, rng=random.Random(3)), every), w=80.0)
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    assert uut.get("fbUut.fTuneNoiseInterval") == pytest.approx(every * TS, rel=0.02)


HOLD_CYCLES = 5  # the TCLab scenario's: a reading every 0.5 s, the controller every 0.1 s


def test_the_filter_is_sized_for_noise_the_sensor_holds_for_several_cycles(uut) -> None:
    """TUNE sizes the filter on the interval the noise holds each value: through the running filter the
    held noise keeps the share of its standard deviation the sizing planned (sized on the cycle, as if
    every reading were new, it kept about twice that)."""
    plant = Fopdt(k=0.9, t=100.0, l=10.0, noise=0.5, rng=random.Random(3))
    sensor = HeldSensor(plant, HOLD_CYCLES)
    run_tune(uut, sensor, w=80.0, extra={"fTuneMsMax": 0.0, "fTuneNoiseKpOutput": 0.0})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    hold = uut.get("fbUut.fTuneNoiseInterval")
    got = identified(uut)
    tf = uut.get("sPar.fTFilterTuned")
    assert tf == pytest.approx(filter_time(got["fKp"], uut.get("sPar.fTuneNoisePp"), 2.0, hold, got["fTu"],
                                           0.1), rel=1e-3)
    assert tf > HOLD_CYCLES * TS
    uut.set("nMode", MODE_ACTIVE)
    errors, raw = [], []
    for k in range(int(600.0 / TS)):
        x = sensor.measure()
        uut.set("fbUut.fX", x)
        uut.scan()
        if k * TS > 20 * tf:
            errors.append(uut.get("fbUut.fXUsed") - plant.x)
            raw.append(x - plant.x)
        sensor.step(uut.get("fbUut.fY"))
    planned = filtered_noise(1.0, tf, hold)
    kept = float(np.std(errors) / np.std(raw))
    print(f"noise held {hold:.2f} s, filter {tf:.2f} s: std kept {kept:.3f}, planned {planned:.3f}")
    assert kept == pytest.approx(planned, rel=0.15)


def test_the_users_filter_wins_and_tune_then_sizes_none(uut) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0, noise=0.5, rng=random.Random(3))
    uut.set("sPar.fTFilterTuned", 0.7)  # from an earlier tuning
    run_tune(uut, plant, w=80.0, extra={"bFilter": True, "fTFilter": 0.4})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    assert uut.get("sPar.fTFilterTuned") == 0.0
    assert uut.get("sPar.fTFilter") == pytest.approx(0.4)
    assert uut.get("fbUut.fTFilterUsed") == pytest.approx(0.4)
    uut.set("sPar.bFilter", False)
    uut.scan()
    assert uut.get("fbUut.fTFilterUsed") == 0.0


def test_a_process_still_drifting_at_rest_is_not_taken_for_noise(uut) -> None:
    """TUNE started while the hot end still cools (3 degC above its rest, T = 140 s): the band it waits in
    holds about 0.4 degC of drift; the noise it publishes is the sensor's (uniform +-0.02 degC), so the
    filter, the derivative filter and AUTO's noise-limited Kp are not sized for the drift."""
    plant = Fopdt(k=3.4, t=140.0, l=5.5, x0=25.0, noise=0.02, rng=random.Random(4))
    plant.x = 28.0
    run_tune(uut, plant, w=200.0, y_tune=60.0)
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    noise = uut.get("sPar.fTuneNoisePp")
    drift = 0.4  # degC the band held over fTuneStabilisation (20 s) at the start of the cool-down
    assert 0.0 < noise < drift / 2, f"published noise {noise:.3f} degC"


@dataclass
class DriftingFopdt(Fopdt):
    """An FOPDT whose rest drifts at `rate` degC/s whatever the output: a neighbour's heat on a coupled
    plant, which the step's record would otherwise carry as the plant's own response."""

    rate: float = 0.0
    elapsed: float = 0.0

    def measure(self) -> float:
        return super().measure() + self.rate * self.elapsed

    def step(self, u: float) -> None:
        super().step(u)
        self.elapsed += self.dt


DRIFT_PLANT = dict(k=0.5, t=200.0, l=10.0, x0=20.0, noise=0.05)
DRIFT_W = 50.0  # the record ends at 80 % of the way, a rise of about 24 degC after about 140 s


@pytest.mark.parametrize(("rate", "refused"), [(0.03, True), (-0.03, True), (0.005, False), (0.0, False)])
def test_a_rest_still_drifting_is_no_rest_to_tune_from(uut, rate: float, refused: bool) -> None:
    """A drift that stays inside the stabilisation band (0.6 degC over its 20 s) but carried over the record
    moves X by more than a tenth of the rise is refused (error 17, no model); one that moves it less, or a
    rest that is flat, tunes."""
    ks_before = uut.get("sPar.fKs")
    run_tune(uut, DriftingFopdt(rate=rate, **DRIFT_PLANT), w=DRIFT_W, y_tune=100.0)
    if refused:
        assert error_of(uut) == 17
        assert uut.get("sPar.fKs") == ks_before, "a refused record changed the model"
    else:
        assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
        assert uut.get("sPar.fKs") == pytest.approx(DRIFT_PLANT["k"], rel=0.1)


def test_a_zone_still_settling_from_its_last_run_still_tunes(uut) -> None:
    """TUNE while the zone still cools from running hotter (4 degC above its rest, T = 100 s): that drift
    decays with the plant's own T, so over the record it moves X by at most drift T (1 - e^(-te/T)), within
    a tenth of the rise, where drift times the record's length would not be."""
    plant = Fopdt(k=0.5, t=100.0, l=5.0, x0=20.0, noise=0.05, rng=random.Random(3))
    plant.x = 24.0
    run_tune(uut, plant, w=65.0, y_tune=100.0)
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    drift, record = abs(uut.get("fbUut.fbTuner.fRestDrift")), uut.get("fbUut.fbTuner.fStepAge")
    rise = uut.get("fbUut.fbTuner.fRise")
    print(f"drift {drift:.3f} degC/s, record {record:.1f} s, rise {rise:.1f} degC")
    assert drift * record > 0.1 * rise, "the rest did not drift enough to tell the two readings apart"


@pytest.mark.parametrize(("noise", "expected_rule"),
                         [(0.0, RULE_AMIGO), (0.02, RULE_AMIGO), (0.05, RULE_SIMC), (0.1, RULE_SIMC)],
                         ids=["no-noise", "quiet", "derivative-alone-quiet", "noisy"])
def test_below_lag_dominated_auto_takes_amigo_where_it_rejects_loads_better_and_noise_allows(
        uut, noise, expected_rule) -> None:
    """tau = 0.05 (a lag-dominated plant): SIMC PI integrates a load step's error to 1.37 x AMIGO's
    (Tn / Kp); AUTO takes AMIGO unless its P and D, at the rule's own filter Td = fTuneTd Tv, would
    move the output by more than fTuneNoiseOutput at the noise TUNE measured (Kp noise (1 + 1 / fTuneTd)),
    also where its derivative alone would stay within the goal."""
    plant = Fopdt(k=2.0, t=95.0, l=5.0, noise=noise, rng=random.Random(3))
    run_tune(uut, plant, w=80.0, y_tune=30.0)
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    got = identified(uut)
    assert simc_load_ratio(got["fKs"], got["fTu"], got["fTg"]) > AMIGO_LOAD_GAIN_MIN
    kp_a = rule_values(RULE_AMIGO, got["fKs"], got["fTu"], got["fTg"], got["fVmax"], 30.0)[0]
    d_noise = kp_a * uut.get("fbUut.fbTuner.fNoise") * (1.0 + 1.0 / uut.get("sPar.fTuneTd"))
    print(f"noise {noise}: AMIGO's P and D would move the output {d_noise:.2f} % p-p "
          f"(goal {uut.get('sPar.fTuneNoiseOutput')}): rule {uut.get('nRuleUsed')}")
    assert (d_noise <= uut.get("sPar.fTuneNoiseOutput")) == (expected_rule == RULE_AMIGO)
    assert uut.get("nRuleUsed") == expected_rule


@pytest.mark.parametrize("kp_limit", [1.0, 2.5, 0.0], ids=["noise-limited", "filter-suffices", "limit-off"])
def test_a_noise_limited_set_is_simc_pi_whatever_rule_auto_picked(uut, kp_limit) -> None:
    """AUTO picks AMIGO here (fTauLagDominated 0); with the noise limit the Kp it can afford is far below
    AMIGO's, and the set written is SIMC PI for that slower loop: Kp = fTuneNoiseKpOutput / filtered noise,
    tau_c = Tg / (Ks Kp) - Tu, Tn = min(Tg + Tu/3, 4 (tau_c + Tu)), no derivative. At a limit the filter can
    meet within its share of the loop's time scale Tg / (Ks Kp), AMIGO's set stays."""
    plant = Fopdt(k=0.9, t=100.0, l=10.0, noise=1.0, rng=random.Random(3))
    run_tune(uut, plant, w=80.0, extra={"fTauLagDominated": 0.0, "fTuneNoiseKpOutput": kp_limit})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    got = identified(uut)
    tf, share = uut.get("sPar.fTFilterTuned"), uut.get("sPar.fTuneFilterLagShare")
    if kp_limit != 1.0:
        assert uut.get("nRuleUsed") == RULE_AMIGO
        assert got["fTv"] > 0.0
        assert got["fSetpointWeight"] == 0.0
        if kp_limit:
            assert got["fKp"] * filtered_noise(uut.get("fbUut.fbTuner.fNoise"), tf, TS) <= kp_limit * 1.001
            assert share * got["fTu"] < tf <= share * got["fTg"] / (got["fKs"] * got["fKp"]) * 1.001
        return
    assert uut.get("nRuleUsed") == RULE_SIMC
    assert (got["fTv"], got["fTd"]) == (0.0, 0.0)
    assert got["fSetpointWeight"] == pytest.approx(setpoint_weight(RULE_SIMC, 0.0, got["fTn"], got["fTg"]),
                                                   rel=1e-5)
    noise_filtered = filtered_noise(uut.get("fbUut.fbTuner.fNoise"), tf, TS)
    assert got["fKp"] == pytest.approx(kp_limit / noise_filtered, rel=1e-3)
    # the filter takes its share of the slower loop's time scale, tau_c + Tu = Tg / (Ks Kp), not of Tu alone
    assert tf == pytest.approx(share * got["fTg"] / (got["fKs"] * got["fKp"]), rel=1e-3)
    assert tf > share * got["fTu"]
    amigo_kp = rule_values(RULE_AMIGO, got["fKs"], got["fTu"], got["fTg"], got["fVmax"], 100.0)[0]
    assert got["fKp"] < amigo_kp
    assert got["fTn"] == pytest.approx(simc_tn(got["fKp"], got["fKs"], got["fTu"], got["fTg"]), rel=1e-3)


def test_a_noise_limited_set_without_a_model_is_simc_pi_on_the_tangent(uut) -> None:
    """A record still straight when the step ends (Ks and Tg not identifiable: CHR on the tangent) from a
    noisy sensor: the noise limits Kp, and the set is SIMC PI for the integrating process the tangent is,
    k' e^(-Tu s) / s with k' = Vmax / dY: tau_c + Tu = 1 / (k' Kp), Tn = 4 (tau_c + Tu), b = 0.69, no
    derivative. Without a model to divide by, Tn is not cut to a share of the delay."""
    plant = Fopdt(k=5.0, t=2000.0, l=8.0, noise=0.1, rng=random.Random(5))
    kp_limit, dy = 2.5, 100.0
    run_tune(uut, plant, w=45.0, y_tune=dy, extra={"fTuneNoiseKpOutput": kp_limit})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    got = identified(uut)
    assert got["fTg"] == 0.0 and got["fKs"] == 0.0
    assert uut.get("nRuleUsed") == RULE_SIMC
    assert (got["fTv"], got["fTd"]) == (0.0, 0.0)
    tf = uut.get("sPar.fTFilterTuned")
    noise_filtered = filtered_noise(uut.get("fbUut.fbTuner.fNoise"), tf, TS)
    assert got["fKp"] == pytest.approx(kp_limit / noise_filtered, rel=1e-3)
    k_prime = got["fVmax"] / dy
    # the filter's share of the loop's time scale, tau_c + Tu = 1 / (k' Kp)
    share = uut.get("sPar.fTuneFilterLagShare")
    assert tf == pytest.approx(share / (k_prime * got["fKp"]), rel=1e-3)
    want_tn = SIMC_TN_FACTOR / (k_prime * got["fKp"])
    kp_chr = rule_values(RULE_CHR, 0.0, got["fTu"], 0.0, got["fVmax"], dy)[0]
    print(f"Kp {got['fKp']:.3f} %/degC (CHR's {kp_chr:.1f}), Tn {got['fTn']:.1f} s "
          f"(4 / (k' Kp) = {want_tn:.1f} s, Tu {got['fTu']:.2f} s), b {got['fSetpointWeight']:.2f}")
    assert got["fTn"] == pytest.approx(want_tn, rel=1e-3)
    assert got["fTn"] > got["fTu"]
    # the weight's limit for Tn far below Tg: an integrating process has no Tg to compare with
    assert got["fSetpointWeight"] == pytest.approx(SIMC_WEIGHT_0, rel=1e-6)


OUTPUT_GOAL_PP = 2.0  # fTuneNoiseOutput's default, % peak-to-peak
AMIGO_PLANT = dict(k=0.9, t=100.0, l=30.0)  # tau = 0.23: AUTO takes AMIGO, a PID


def output_noise_pp(uut: ScanDriver, plant: Fopdt, settle_s: float = 700.0, hold_s: float = 800.0) -> float:
    """The tuned set holding the setpoint: the output's standard deviation, as peak-to-peak in the unit TUNE
    measured the noise in (std of Y / std of the sensor noise x the noise's measured peak-to-peak)."""
    uut.set("nMode", MODE_ACTIVE)
    ys = []
    for _ in range(int((settle_s + hold_s) / TS)):
        uut.set("fbUut.fX", plant.measure())
        uut.scan()
        ys.append(uut.get("fbUut.fY"))
        plant.step(ys[-1])
    held = np.array(ys[int(settle_s / TS):])
    return float(held.std() / (plant.noise / math.sqrt(3.0)) * uut.get("fbUut.fbTuner.fNoise"))


@pytest.mark.parametrize(("noise", "share", "rule"),
                         [(0.15, 0.1, RULE_AUTO), (0.5, 0.1, RULE_AUTO), (0.5, 0.001, RULE_AUTO),
                          (0.5, 0.1, RULE_AMIGO)],
                         ids=["derivative-filter", "actual-value-filter", "at-the-lag-bound", "named-rule"])
def test_p_and_d_together_move_the_output_by_at_most_the_noise_goal(uut, noise, share, rule) -> None:
    """P and D act on the same X and move the output in phase: Kp nf (1 + Tv / Td). AUTO sizes the filter
    for 2 Kp (D at its quietest, Td = Tv) and gives D what P leaves of the goal, so the sum meets it; at the
    filter's lag bound D is at its quietest. A rule chosen by name holds each part to the goal on its own,
    and its output moves up to twice as much. Checked on the formula and on the output of the loop holding
    its setpoint."""
    plant = Fopdt(**AMIGO_PLANT, noise=noise, rng=random.Random(3))
    run_tune(uut, plant, w=80.0, rule=rule, extra={"fTuneFilterLagShare": share, "fTuneMsMax": 0.0,
                                                   "fTuneNoiseKpOutput": 0.0})
    assert uut.get("nTuneState") == TUNE_READY, uut.get("fbUut.nErrorId")
    assert uut.get("nRuleUsed") == RULE_AMIGO
    got = identified(uut)
    kp, tv, td = got["fKp"], got["fTv"], got["fTd"]
    noise_pp, tf = uut.get("fbUut.fbTuner.fNoise"), uut.get("sPar.fTFilterTuned")
    nf = filtered_noise(noise_pp, tf, TS)
    td_rule = uut.get("sPar.fTuneTd") * tv
    planned = kp * nf * (1.0 + tv / td)
    if rule == RULE_AUTO:
        gain = 2.0 * kp
        p_left = OUTPUT_GOAL_PP - kp * nf
        want_td = tv if p_left <= 0.0 else min(max(td_rule, kp * tv * nf / p_left), tv)
    else:
        gain = kp
        want_td = min(max(td_rule, kp * tv * nf / OUTPUT_GOAL_PP), tv)
    assert tf == pytest.approx(filter_time(gain, noise_pp, OUTPUT_GOAL_PP, TS, got["fTu"], share), rel=1e-3,
                               abs=1e-6)
    assert td == pytest.approx(want_td, rel=1e-3)
    measured = output_noise_pp(uut, plant)
    print(f"{rule=} noise {noise_pp:.3f} p-p: filter {tf:.3f} s, Td {td:.2f} s of Tv {tv:.2f} s; "
          f"P and D planned {planned:.2f} % p-p, measured {measured:.2f} % p-p (goal {OUTPUT_GOAL_PP})")
    assert measured == pytest.approx(planned, rel=0.1)
    at_bound = tf >= share * got["fTu"] * (1.0 - 1e-4)
    if rule == RULE_AUTO and not at_bound:
        assert planned == pytest.approx(OUTPUT_GOAL_PP, rel=1e-3)
    elif rule == RULE_AUTO:
        assert td == pytest.approx(tv, rel=1e-6)
    else:
        assert planned > 1.5 * OUTPUT_GOAL_PP
