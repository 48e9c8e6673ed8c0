"""Generates plc/app/P_ThermoST.st (the OpenPLC application PROGRAM and its register map).

The PROGRAM repeats the same register block per zone; this script writes it once so the zones cannot
drift apart. Run `python plc/app/gen_p_thermost.py` after editing it and commit both files.
The .st file is the source of truth for the register map (modbus_bridge.regmap parses it).
"""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path


def _sibling(name: str):
    """Load a generator module next to this file (the script runs without the package on sys.path)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


gen_fuzzy_block = _sibling("gen_fuzzy_block")

OUT = Path(__file__).with_name("P_ThermoST.st")
MD_ZONE_STRIDE = 100
MW_ZONE_STRIDE = 20

# (suffix, sParam field, type, comment): read/write parameters, synchronised both ways
# (a Modbus write changes the parameter; a change inside the controller, e.g. TUNE, shows in the register)
PARAMS: list[tuple[str, str, str, str]] = [
    ("fKp", "fKp", "REAL", "Kp heating, %/degC (written by TUNE)"),
    ("fTn", "fTn", "REAL", "Tn heating, s; <= 0: no I part (written by TUNE)"),
    ("fTv", "fTv", "REAL", "Tv heating, s (written by TUNE)"),
    ("fTd", "fTd", "REAL", "Td heating (D-T1 damping), s (written by TUNE)"),
    ("fKpCool", "fKpCool", "REAL", "Kp cooling, %/degC"),
    ("fTnCool", "fTnCool", "REAL", "Tn cooling, s"),
    ("fTvCool", "fTvCool", "REAL", "Tv cooling, s"),
    ("fTdCool", "fTdCool", "REAL", "Td cooling, s"),
    ("fYMin", "fYMin", "REAL", "output lower limit, % (-100 .. fYMax)"),
    ("fYMax", "fYMax", "REAL", "output upper limit, % (fYMin .. 100)"),
    ("fCtrlCycleTime", "fCtrlCycleTime", "REAL", "control cycle, s (multiple of the task cycle)"),
    ("fTaskCycleTime", "fTaskCycleTime", "REAL", "task cycle the controller assumes, s (TASK INTERVAL)"),
    ("fPwmPeriod", "fPwmPeriod", "REAL", "PWM period, s"),
    ("fPwmMinOn", "fPwmMinOn", "REAL", "PWM minimum pulse, s"),
    ("fPwmMinOff", "fPwmMinOff", "REAL", "PWM minimum pause, s"),
    ("fWMin", "fWMin", "REAL", "setpoint range low, degC"),
    ("fWMax", "fWMax", "REAL", "setpoint range high, degC"),
    ("fWVeloPos", "fWVeloPos", "REAL", "setpoint ramp up, degC/s (coil bEnableRamping)"),
    ("fWVeloNeg", "fWVeloNeg", "REAL", "setpoint ramp down, degC/s"),
    ("fWStartUp", "fWStartUp", "REAL", "soft-start plateau, degC"),
    ("fTStartUp", "fTStartUp", "REAL", "soft-start hold time, s"),
    ("fWStartUpVelo", "fWStartUpVelo", "REAL", "soft-start ramp, degC/s"),
    ("fTFilter", "fTFilter", "REAL", "actual-value filter time constant, s (coil bFilter)"),
    ("fYTune", "fYTune", "REAL", "TUNE step amplitude, % (negative: cooling set)"),
    ("fYStable", "fYStable", "REAL", "TUNE output while waiting for a steady X, %"),
    ("fTuneStabilisation", "fTuneStabilisation", "REAL", "TUNE stabilisation time, s"),
    ("fTuneBand", "fTuneBand", "REAL", "TUNE stabilisation band, degC"),
    ("fEndTunePercent", "fEndTunePercent", "REAL", "TUNE ends at this % of the way X0 -> W"),
    ("fTuneTimeout", "fTuneTimeout", "REAL", "TUNE timeout, s"),
    ("fTuneSlopeWindow", "fTuneSlopeWindow", "REAL", "TUNE slope differencing window, s"),
    ("fTuneNoiseRatio", "fTuneNoiseRatio", "REAL", "TUNE: rise must exceed this many noise bands"),
    ("fSimcTauCFactor", "fSimcTauCFactor", "REAL", "SIMC tau_c / Tu"),
    ("fTempLow", "fTempLow", "REAL", "alarm band 1 below W, degC"),
    ("fTempLowLow", "fTempLowLow", "REAL", "alarm band 2 below W, degC"),
    ("fTempHigh", "fTempHigh", "REAL", "alarm band 1 above W, degC"),
    ("fTempHighHigh", "fTempHighHigh", "REAL", "alarm band 2 above W, degC"),
    ("fTempAbsHigh", "fTempAbsHigh", "REAL", "absolute high limit, degC"),
    ("fTempAbsLow", "fTempAbsLow", "REAL", "absolute low limit, degC"),
    ("fXMin", "fXMin", "REAL", "plausible X low (below: sensor short), degC"),
    ("fXMax", "fXMax", "REAL", "plausible X high (above: sensor open), degC"),
    ("fRunawayHysteresis", "fRunawayHysteresis", "REAL", "runaway: allowed drop below W, degC"),
    ("fRunawayPeriod", "fRunawayPeriod", "REAL", "runaway: for at most, s (0 = off)"),
    ("fWatchPeriod", "fWatchPeriod", "REAL", "heat-up watch period, s (0 = off)"),
    ("fWatchIncrease", "fWatchIncrease", "REAL", "heat-up watch: required rise, degC"),
    ("fWatchYMin", "fWatchYMin", "REAL", "heat-up watch active above this output, %"),
    ("fYOnFailure", "fYOnFailure", "REAL", "output for reaction FAILVALUE, %"),
    ("dwAlarmSupp", "dwAlarmSupp", "DWORD", "alarm suppression mask (alarm bits)"),
    ("dwAlarmReaction", "dwAlarmReaction", "DWORD", "alarms that trigger the reaction"),
]
# identified plant, read only
IDENT: list[tuple[str, str, str]] = [
    ("fKs", "fKs", "identified plant gain, degC/% (0: not identifiable)"),
    ("fTu", "fTu", "identified delay time Tu (L), s"),
    ("fTg", "fTg", "identified lag time Tg (T), s (0: not identifiable)"),
    ("fVmax", "fVmax", "maximum slope during the TUNE step, degC/s"),
    ("fTauNorm", "fTauNorm", "normalised dead time Tu/(Tu+Tg)"),
]
# FB outputs, read only
OUTPUTS: list[tuple[str, str, str, str]] = [
    ("fXUsed", "fXUsed", "REAL", "actual value used (after raw scaling and filter), degC"),
    ("fWWork", "fW", "REAL", "working setpoint (after ramp / soft start), degC"),
    ("fE", "fE", "REAL", "control error W - X, degC"),
    ("fP", "fP", "REAL", "P part, %"),
    ("fI", "fI", "REAL", "I part, %"),
    ("fD", "fD", "REAL", "D part, %"),
    ("fMaxOverShoot", "fMaxOverShoot", "REAL", "largest overshoot since W was reached, degC"),
    ("fStartUpTime", "fStartUpTime", "REAL", "time from ACTIVE until W was first reached, s"),
]


HEADER = """
(* P_ThermoST: OpenPLC application of ThermoST. Two FB_TempController zones after seed 000's
   bioprinter: zone 1 = nozzle (heater, 100 kOhm NTC as on seed 002's hot end), zone 2 = forming
   platform (compressor cooling + heater, PT100, output -100 .. +100 %). The located variables below
   ARE the Modbus register map (OpenPLC v3: %MDn = holding 2048+2n, %MWn = holding 1024+n,
   %QXa.b = coil 8a+b, %IWn = input register n); docs/register-map.md is generated from them.
   Process value from %MD (harness) or, with coil bUseRaw, from the raw %IW through the sensor
   functions. Parameters written over Modbus are checked in ST (FB_CtrlParamCheck); unknown mode /
   rule / reaction codes keep the last valid one and set alarm bit 16. A parameter register is copied
   into the controller only when a client changed it, and always shows the value in use, so TUNE
   results appear in fKp/fTn/fTv/fTd.
   Reserved for the fuzzy gain adapter (FB_FuzzyGainAdapter, helper 'fuzzy'): %MD200..%MD299 and
   coils %QX4.0..%QX4.7 (per-zone enable, e.g. bFuzzyZone1 AT %QX4.0, bFuzzyZone2 AT %QX4.1).
   Generated by plc/app/gen_p_thermost.py. *)
"""


@dataclass
class Zone:
    n: int
    title: str
    sensor: str  # "ntc" or "pt100"
    defaults: str  # named initial values of ST_ControllerParameter
    sensor_params: list[tuple[str, float, str]]


ZONES = [
    Zone(1, "nozzle (seed 000 / seed 002 hot end: heater only, 100 kOhm NTC on a divider)", "ntc",
         "fKp := 3.7, fTn := 44.0, fTv := 0.0, fTd := 0.0, fYMin := 0.0, fYMax := 100.0, fWMin := 0.0, "
         "fWMax := 300.0, fYTune := 60.0, fTempAbsHigh := 290.0, fTempAbsLow := -20.0, fXMin := -30.0, "
         "fXMax := 320.0, fPwmPeriod := 1.0, fWatchPeriod := 45.0, fRunawayPeriod := 40.0",
         [("fNtcR25", 100000.0, "NTC resistance at 25 degC, ohm"),
          ("fNtcBeta", 3950.0, "NTC beta, K"),
          ("fRPullup", 4700.0, "divider pull-up, ohm")]),
    Zone(2, "forming platform (seed 000: compressor cooling + heater, PT100)", "pt100",
         "fKp := 10.0, fTn := 150.0, fTv := 0.0, fTd := 0.0, fKpCool := 10.0, fTnCool := 150.0, "
         "fYMin := -100.0, fYMax := 100.0, fWMin := -10.0, fWMax := 60.0, fYTune := 50.0, "
         "fTempAbsHigh := 50.0, fTempAbsLow := -15.0, fXMin := -50.0, fXMax := 150.0, fPwmPeriod := 2.0, "
         "fWatchPeriod := 60.0, fWatchYMin := 90.0, fRunawayPeriod := 120.0",
         [("fRawResLow", 18.52, "PT100 resistance at raw count 0, ohm (-200 degC)"),
          ("fRawResHigh", 390.48, "PT100 resistance at raw count 32767, ohm (850 degC)"),
          ("fPt100R0", 100.0, "RTD R0, ohm")]),
]


def zone_decls(z: Zone) -> tuple[list[str], list[str]]:
    """(located declarations, internal declarations)."""
    n, md, mw = z.n, (z.n - 1) * MD_ZONE_STRIDE, (z.n - 1) * MW_ZONE_STRIDE
    loc: list[str] = [f"    (* ---- zone {n}: {z.title} ---- *)"]

    def add(name: str, where: str, typ: str, comment: str) -> None:
        loc.append(f"    {name}Zone{n} AT {where} : {typ}; (* {comment} *)")

    add("fPv", f"%MD{md + 0}", "REAL", "process value written by the harness, degC (used unless bUseRaw)")
    add("fSetpoint", f"%MD{md + 1}", "REAL", "setpoint W1, degC")
    add("fSetpointStandby", f"%MD{md + 2}", "REAL", "standby setpoint W2, degC (coil bSelSetpoint)")
    add("fYManual", f"%MD{md + 3}", "REAL", "manual output, % (mode MANUAL)")
    add("fY", f"%MD{md + 4}", "REAL", "analog control value, % (-100 .. +100)")
    add("dwAlarm", f"%MD{md + 5}", "DWORD", "alarm word (docs/library.md: alarm bits)")
    idx = 6
    for suffix, _field, typ, comment in PARAMS:
        add(suffix, f"%MD{md + idx}", typ, comment)
        idx += 1
    for suffix, _field, comment in IDENT:
        add(suffix, f"%MD{md + idx}", "REAL", comment)
        idx += 1
    for suffix, _field, typ, comment in OUTPUTS:
        add(suffix, f"%MD{md + idx}", typ, comment)
        idx += 1
    for suffix, _value, comment in z.sensor_params:
        add(suffix, f"%MD{md + idx}", "REAL", comment)
        idx += 1
    assert idx < MD_ZONE_STRIDE
    add("nMode", f"%MW{mw + 0}", "INT", "mode: 0 IDLE 1 PASSIVE 2 ACTIVE 3 RESET 4 MANUAL 5 TUNE")
    add("nState", f"%MW{mw + 1}", "INT",
        "state: 0 IDLE 1 PASSIVE 2 ACTIVE 3 RESET 4 MANUAL 5 TUNING 6 TUNED 8 ERROR")
    add("nTuneState", f"%MW{mw + 2}", "INT", "tuning: 0 OFF 1 INIT 2 IDLE 3 STEP 4 READY 5 ERROR")
    add("nErrorId", f"%MW{mw + 3}", "INT", "error id (docs/library.md)")
    add("nTuneRule", f"%MW{mw + 4}", "INT", "tuning rule: 0 AUTO 1 CHR 2 COHEN_COON 3 SIMC")
    add("nTuneRuleUsed", f"%MW{mw + 5}", "INT", "rule that produced the current set")
    add("nReaction", f"%MW{mw + 6}", "INT", "reaction on failure: 0 NONE 1 OFF 2 FAILVALUE 3 HOLD")
    add("nRawShort", f"%MW{mw + 7}", "INT", "raw count at or below: sensor short")
    add("nRawOpen", f"%MW{mw + 8}", "INT", "raw count at or above: sensor open")
    add("nPvRawModbus", f"%MW{mw + 9}", "INT", "raw counts written by a Modbus client (coil bRawFromModbus)")
    add("nPvRaw", f"%IW{n - 1}", "INT", "raw analog input, counts 0 .. 32767")
    q = n - 1
    add("bPwmHeat", f"%QX{q}.0", "BOOL", "heating PWM output")
    add("bPwmCool", f"%QX{q}.1", "BOOL", "cooling PWM output")
    add("bUseRaw", f"%QX{q}.2", "BOOL", "TRUE: X from nPvRaw through the sensor functions")
    add("bAck", f"%QX{q}.3", "BOOL", "write TRUE: acknowledge alarms (self-resetting)")
    add("bSelSetpoint", f"%QX{q}.4", "BOOL", "TRUE: standby setpoint W2")
    add("bEnableRamping", f"%QX{q}.5", "BOOL", "setpoint ramp on")
    add("bEnableSoftStart", f"%QX{q}.6", "BOOL", "soft start on")
    add("bFilter", f"%QX{q}.7", "BOOL", "actual-value filter on")
    add("bError", f"%QX{q + 2}.0", "BOOL", "controller error (state ERROR)")
    add("bAlarmLatch", f"%QX{q + 2}.1", "BOOL", "alarms latch until acknowledged")
    add("bARWOnIPartOnly", f"%QX{q + 2}.2", "BOOL", "anti-windup clamps only the I part")
    add("bRawFromModbus", f"%QX{q + 2}.3", "BOOL", "bUseRaw: counts from nPvRawModbus, not %IW")
    md_end, mw_end = md + MD_ZONE_STRIDE - 1, mw + MW_ZONE_STRIDE - 1
    loc.append(f"    (* zone {n}: %MD{md + idx}..%MD{md_end}, %MW{mw + 10}..%MW{mw_end}, "
               f"%QX{q + 2}.4..%QX{q + 2}.7 free *)")

    internal = [
        f"    sParZone{n} : ST_ControllerParameter := ({z.defaults});",
        f"    fbZone{n} : FB_TempController;",
        f"    eModeZone{n} : E_CtrlMode := eCTRL_MODE_IDLE;",
        f"    fXZone{n} : REAL;",
        f"    fResZone{n} : REAL;",
        f"    nRawZone{n} : INT;",
        f"    bRawOpenZone{n} : BOOL;",
        f"    bRawShortZone{n} : BOOL;",
        f"    bRejectedZone{n} : BOOL;",
        f"    bOneRejectZone{n} : BOOL;",
    ]
    for suffix, _f, typ, _c in PARAMS:
        internal.append(f"    {suffix}PrevZone{n} : {typ};")
    return loc, internal


def fuzzy_decls(z: Zone) -> tuple[list[str], list[str]]:
    """The fuzzy gain adapter's (located declarations in %MD200..%MD299 / %QX4.0..%QX4.7, internal
    declarations) of zone z; see gen_fuzzy_block.py and docs/fuzzy.md."""
    return gen_fuzzy_block.fuzzy_decls(z)


def fuzzy_body(z: Zone) -> list[str]:
    """The fuzzy gain adapter's ST lines, run before zone z's controller call."""
    return gen_fuzzy_block.fuzzy_body(z)


def zone_init(z: Zone) -> list[str]:
    n = z.n
    lines = [f"    (* zone {n}: registers start from the parameter defaults *)"]
    for suffix, field, _t, _c in PARAMS:
        lines.append(f"    {suffix}Zone{n} := sParZone{n}.{field};")
        lines.append(f"    {suffix}PrevZone{n} := {suffix}Zone{n};")
    for suffix, value, _c in z.sensor_params:
        lines.append(f"    {suffix}Zone{n} := {value!r};")
    lines += [
        f"    nRawShortZone{n} := 16;",
        f"    nRawOpenZone{n} := 32751;",
        f"    nReactionZone{n} := 1;",
        f"    bAlarmLatchZone{n} := sParZone{n}.bAlarmLatch;",
    ]
    return lines


def zone_body(z: Zone) -> list[str]:
    n = z.n
    b = [f"  (* ================= zone {n}: {z.title} ================= *)"]
    b.append("  (* Modbus -> parameters: only registers a client changed (TUNE results stay) *)")
    for suffix, field, _t, _c in PARAMS:
        reg = f"{suffix}Zone{n}"
        b.append(f"  IF {reg} <> {suffix}PrevZone{n} THEN sParZone{n}.{field} := {reg}; END_IF;")
    b += [
        f"  bRejectedZone{n} := FALSE;",
        f"  eModeZone{n} := FC_CtrlModeFromInt(nMode := nModeZone{n}, eLastValid := eModeZone{n},"
        f" bRejected => bOneRejectZone{n});",
        f"  bRejectedZone{n} := bRejectedZone{n} OR bOneRejectZone{n};",
        f"  sParZone{n}.eTuneRule := FC_TuneRuleFromInt(nRule := nTuneRuleZone{n},"
        f" eLastValid := sParZone{n}.eTuneRule, bRejected => bOneRejectZone{n});",
        f"  bRejectedZone{n} := bRejectedZone{n} OR bOneRejectZone{n};",
        f"  sParZone{n}.eReactionOnFailure := FC_ReactionFromInt(nReaction := nReactionZone{n},"
        f" eLastValid := sParZone{n}.eReactionOnFailure, bRejected => bOneRejectZone{n});",
        f"  bRejectedZone{n} := bRejectedZone{n} OR bOneRejectZone{n};",
        f"  sParZone{n}.bEnableRamping := bEnableRampingZone{n};",
        f"  sParZone{n}.bEnableSoftStart := bEnableSoftStartZone{n};",
        f"  sParZone{n}.bFilter := bFilterZone{n};",
        f"  sParZone{n}.bAlarmLatch := bAlarmLatchZone{n};",
        f"  sParZone{n}.bARWOnIPartOnly := bARWOnIPartOnlyZone{n};",
        "",
        "  (* actual value: harness value or raw input through the sensor functions *)",
        f"  bRawOpenZone{n} := FALSE;",
        f"  bRawShortZone{n} := FALSE;",
        f"  IF bUseRawZone{n} THEN",
        f"    IF bRawFromModbusZone{n} THEN",
        f"      nRawZone{n} := nPvRawModbusZone{n};",
        "    ELSE",
        f"      nRawZone{n} := nPvRawZone{n};",
        "    END_IF;",
        f"    bRawOpenZone{n} := nRawZone{n} >= nRawOpenZone{n};",
        f"    bRawShortZone{n} := nRawZone{n} <= nRawShortZone{n};",
    ]
    if z.sensor == "ntc":
        b += [
            f"    fResZone{n} := FC_NtcDividerResistance(nRaw := nRawZone{n}, nRawFull := nRawFullScale,"
            f" fRPullup := fRPullupZone{n}, fROpen := fROpenCircuit);",
            f"    IF fResZone{n} > 0.0 THEN",
            f"      fXZone{n} := FC_NtcBetaToTemp(fResistance := fResZone{n}, fR25 := fNtcR25Zone{n},"
            f" fBeta := fNtcBetaZone{n});",
            "    ELSE",
            f"      fXZone{n} := sParZone{n}.fXMax;",
            "      (* NTC shorted reads as very hot; the raw check above raises the sensor-short bit *)",
            "    END_IF;",
        ]
    else:
        b += [
            f"    fResZone{n} := FC_ScaleRaw(nRaw := nRawZone{n}, nRawLow := 0, nRawHigh := nRawFullScale,"
            f" fLow := fRawResLowZone{n}, fHigh := fRawResHighZone{n});",
            f"    fXZone{n} := FC_Pt100ToTemp(fResistance := fResZone{n}, fR0 := fPt100R0Zone{n});",
        ]
    b += [
        "  ELSE",
        f"    fXZone{n} := fPvZone{n};",
        "  END_IF;",
        "",
        f"  (* fuzzy adapter of zone {n} goes here (before the controller call), see the reserved block *)",
        *fuzzy_body(z),
        "",
        f"  fbZone{n}(eCtrlMode := eModeZone{n}, bSelSetpoint := bSelSetpointZone{n},",
        f"           fW1 := fSetpointZone{n},",
        f"           fW2 := fSetpointStandbyZone{n}, fX := fXZone{n}, fYManual := fYManualZone{n},",
        f"           bOpenThermocouple := bRawOpenZone{n}, bSensorShort := bRawShortZone{n},"
        f" bAckAlarm := bAckZone{n},",
        f"           sParam := sParZone{n});",
        f"  bAckZone{n} := FALSE;",
        "",
        "  (* controller -> Modbus *)",
        f"  fYZone{n} := fbZone{n}.fY;",
        f"  bPwmHeatZone{n} := fbZone{n}.bYPWMPos;",
        f"  bPwmCoolZone{n} := fbZone{n}.bYPWMNeg;",
        f"  dwAlarmZone{n} := fbZone{n}.dwAlarm;",
        f"  IF bRejectedZone{n} THEN",
        f"    dwAlarmZone{n} := dwAlarmZone{n} OR dwParamErrorBit;",
        "  END_IF;",
        f"  bErrorZone{n} := fbZone{n}.bError;",
        f"  nErrorIdZone{n} := fbZone{n}.nErrorId;",
        f"  nStateZone{n} := FC_CtrlStateToInt(eState := fbZone{n}.eCtrlState);",
        f"  nTuneStateZone{n} := FC_CtrlTuneStateToInt(eTuneState := fbZone{n}.eTuneState);",
        f"  nTuneRuleUsedZone{n} := FC_TuneRuleToInt(eRule := sParZone{n}.eTuneRuleUsed);",
    ]
    for suffix, field, _c in IDENT:
        b.append(f"  {suffix}Zone{n} := sParZone{n}.{field};")
    for suffix, field, _t, _c in OUTPUTS:
        b.append(f"  {suffix}Zone{n} := fbZone{n}.{field};")
    for suffix, field, _t, _c in PARAMS:
        b.append(f"  {suffix}Zone{n} := sParZone{n}.{field};")
        b.append(f"  {suffix}PrevZone{n} := {suffix}Zone{n};")
    return b


def generate() -> str:
    out = HEADER.strip("\n").split("\n") + [
        "PROGRAM P_ThermoST",
    ]
    internal_all: list[str] = []
    for z in ZONES:
        loc, internal = zone_decls(z)
        out.append("  VAR")
        out += loc
        out.append("  END_VAR")
        internal_all += internal
    fuzzy_loc: list[str] = []
    for z in ZONES:
        loc, internal = fuzzy_decls(z)
        fuzzy_loc += loc
        internal_all += internal
    out.append("  (* fuzzy adapter registers: %MD200..%MD299 and %QX4.0..%QX4.7 (helper fuzzy) *)")
    if fuzzy_loc:
        out += ["  VAR", *fuzzy_loc, "  END_VAR"]
    out += [
        "  VAR",
        "    bInitDone : BOOL;",
    ]
    out += internal_all
    out += [
        "  END_VAR",
        "  VAR CONSTANT",
        "    nRawFullScale : INT := 32767;",
        "    fROpenCircuit : REAL := 1.0E9;",
        "    dwParamErrorBit : DWORD := 16#00010000;",
        "  END_VAR",
        "",
        "  IF NOT bInitDone THEN",
    ]
    for z in ZONES:
        out += zone_init(z)
    out += ["    bInitDone := TRUE;", "  END_IF;", ""]
    for z in ZONES:
        out += zone_body(z)
        out.append("")
    out.append("END_PROGRAM")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    OUT.write_text(generate())
    print(f"wrote {OUT}")
