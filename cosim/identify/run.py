"""``pneumorail identify``: fit scenario keys to measured data and write what came out; and
``--plan``: which sine excitation identifies k best on a given rig.

Outputs (in ``--out``): ``identify.json`` (estimates, standard errors, 95 % profile intervals,
one-sided at a limit; the correlation matrix; the noise estimated per channel; warnings;
provenance), ``fit.csv`` (measured, predicted and residual per channel), ``residuals.png`` and
``profile_<key>.png``.
"""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Dict, List, Sequence

import numpy as np

from cosim.errors import ScenarioError
from cosim.identify.data import Measurements, read_measurements
from cosim.identify.fit import K_KEY, Identification, fit_joint, fit_k, searched
from cosim.identify.model import RigModel
from cosim.results.plots import Curve, Panel, save_panels
from cosim.scenario.yaml_input import MAX_BYTES
from pneumatics.rig import run_time_series, sine_motion
from pneumorail.files import read_bytes

#: what each channel is called on a plot, with its unit and the scale it is drawn in
LABELS = {"F_bellow_N": ("bellow force F [kN]", 1e-3), "p_bellow_Pa": ("bellow pressure [bar abs]", 1e-5),
          "p_tank_Pa": ("tank pressure [bar abs]", 1e-5), "T_bellow_K": ("bellow temperature [K]", 1.0),
          "T_tank_K": ("tank temperature [K]", 1.0), "K_abs_N_per_m": ("|K*| [kN/m]", 1e-3),
          "loss_angle_deg": ("loss angle [deg]", 1.0), "K_storage_N_per_m": ("K' [kN/m]", 1e-3),
          "K_loss_N_per_m": ("K'' [kN/m]", 1e-3)}


def parse_keys(text: str, scenario_file) -> List[str]:
    keys = [k.strip() for k in text.split(",") if k.strip()]
    if not keys:
        raise ScenarioError(scenario_file, ["--fit"], "name at least one key, e.g. --fit k_W_per_K")
    if len(set(keys)) != len(keys):
        raise ScenarioError(scenario_file, ["--fit"], f"a key appears twice in {text!r}")
    return sorted(keys, key=lambda k: k != K_KEY)              # k first


def identify(scenario_file: Path, data_file: Path, keys: Sequence[str], overrides: Sequence[str] = (),
             executor=None, jobs: int = 1) -> tuple[RigModel, Identification]:
    """Read, check (before anything is simulated) and fit (a stiffness table's frequencies on
    ``jobs`` processes)."""
    data = read_measurements(data_file)
    model = RigModel(Path(scenario_file), tuple(overrides), data, jobs)
    params = searched(model, keys)                            # every key checked before the first simulation
    try:
        return model, (fit_k(model) if list(keys) == [K_KEY] else fit_joint(model, params, executor))
    finally:
        model.close()


def _sha256(path: Path) -> str:
    """The scenario's sha256, read again by the one reader (it may have changed since)."""
    return hashlib.sha256(read_bytes(path, "scenario file", MAX_BYTES, error=ScenarioError)).hexdigest()


def _number(v: float):
    return v if math.isfinite(v) else ("inf" if v > 0 else "-inf" if v < 0 else "nan")


def write(model: RigModel, result: Identification, out: Path) -> List[Path]:
    """identify.json, fit.csv and the figures."""
    out.mkdir(parents=True, exist_ok=True)
    data = model.data
    summary = {
        "scenario_file": str(model.scenario_file), "scenario_sha256": _sha256(model.scenario_file),
        "data_file": str(data.file), "data_sha256": data.sha256, "overrides": list(model.overrides),
        "estimates": [{"key": e.key, "value": _number(e.value), "standard_error": _number(e.se),
                       "ci95_low": _number(e.ci_low), "ci95_high": _number(e.ci_high), "limit": e.limit,
                       "identifiable": e.identifiable} for e in result.estimates],
        "correlation": [[_number(float(v)) for v in row] for row in result.correlation],
        "noise_per_channel": result.sigma, "cost": result.cost, "points": result.n,
        "warnings": result.warnings, "model_batches": result.evaluations, "wall_s": result.wall_s,
    }
    paths = [out / "identify.json"]
    paths[0].write_text(json.dumps(summary, indent=2) + "\n")
    header = [data.x_name] + [f"{c}_{w}" for c in data.channels for w in ("measured", "predicted", "residual")]
    rows = [data.x] + [a for c, v in data.channels.items() for a in (v, result.predicted[c], result.predicted[c] - v)]
    np.savetxt(out / "fit.csv", np.column_stack(rows), delimiter=",", header=",".join(header), comments="", fmt="%.10g")
    paths.append(out / "fit.csv")
    xlabel = "time t [s]" if data.kind == "time" else "frequency f [Hz]"
    panels = []
    for c, v in data.channels.items():
        label, scale = LABELS[c]
        panels.append(Panel([Curve(data.x, v * scale, "measured", "." if data.kind == "table" else "-"),
                             Curve(data.x, result.predicted[c] * scale, "fitted model")], xlabel, label,
                            logx=data.kind == "table"))
        panels.append(Panel([Curve(data.x, (v - result.predicted[c]) / result.sigma[c], "residual / noise")],
                            xlabel, f"{c}: residual / sigma [-]", logx=data.kind == "table",
                            hlines=[(2.0, "+2"), (-2.0, "-2")]))
    fitted = ", ".join(_text(e) for e in result.estimates)
    paths.append(save_panels(out / "residuals.png", panels, f"Measured against fitted: {fitted}", ncols=2))
    for p in result.profiles:
        ok = np.isfinite(p.values) & (p.values > 0) & np.isfinite(p.delta_S)
        near = ok & (p.delta_S <= 10.0 * p.threshold)            # the minimum and the interval's ends
        xlabel = "k [W/K]" if p.key == K_KEY else p.key
        panels = [Panel([Curve(p.values[sel], p.delta_S[sel], "profile", "o-")], xlabel, "S - S_min [-]",
                        title, logx=True, hlines=[(p.threshold, "95 % (chi² 3.84)")])
                  for sel, title in ((ok, "over the search range"), (near, "near the minimum"))]
        paths.append(save_panels(out / f"profile_{p.key.replace('.', '_')}.png", panels,
                                 f"Profile of {p.key}: {_text(next(e for e in result.estimates if e.key == p.key))}"))
    return paths


def _text(e) -> str:
    if e.limit in ("0", "inf"):
        return (f"{e.key} = {e.limit} (the {'adiabatic' if e.limit == '0' else 'isothermal'} limit), 95 % interval "
                f"{e.ci_low:.4g} ... {e.ci_high:.4g}")
    return f"{e.key} = {e.value:.4g} ± {e.se:.2g} (95 % interval {e.ci_low:.4g} ... {e.ci_high:.4g})"


def report(result: Identification) -> str:
    """The result as text for the terminal."""
    lines = [_text(e) + ("  [at the search bound]" if e.limit == "bound" else "") for e in result.estimates]
    if len(result.estimates) > 1:
        keys = [e.key for e in result.estimates]
        lines.append("correlation: " + "; ".join(f"{a} / {b}: {result.correlation[i, j]:+.3f}" for i, a in enumerate(keys)
                                                 for j, b in enumerate(keys) if j > i))
    lines.append("noise estimated from the residuals: " + ", ".join(f"{c} {s:.3g}" for c, s in result.sigma.items()))
    lines += [f"warning: {w}" for w in result.warnings]
    lines.append(f"{result.n} points, {result.evaluations} model evaluations (batches), {result.wall_s:.1f} s")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------ plan
#: a plan's excitation must keep the model valid (cosim.limits.validity): pipe flow below Mach 0.3
#: (eq. 5 is an incompressible law), air between 200 and 400 K
MAX_MACH = 0.3
T_RANGE_K = (200.0, 400.0)
#: candidate sine frequencies of ``--plan`` [Hz]
PLAN_FREQUENCIES = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0)


def plan(scenario_file: Path, k_W_per_K: float, noise: Dict[str, float], overrides: Sequence[str] = (),
         frequencies: Sequence[float] = PLAN_FREQUENCIES) -> List[Dict[str, float]]:
    """For each candidate frequency, a sine of the scenario's amplitude and duration: the standard
    error of k it would give (Cramér-Rao: 1/sqrt(Fisher information of log k) from the
    sensitivity of each noisy channel, sum over samples of (dy/dlog k)^2 / sigma^2), at a
    nominal k. The information sums over samples, so it grows with the duration; what the plan
    compares is where the thermal time constant meets the excitation."""
    from cosim.kinds import KINDS
    from cosim.load import load_scenario
    if not (math.isfinite(k_W_per_K) and k_W_per_K > 0):
        # the standard error is taken with respect to log k at the nominal k: 0, inf, nan or a
        # negative k has no logarithm (inf also makes the rig isothermal: nothing to identify)
        raise ScenarioError(scenario_file, ["--k"], f"the nominal k must be a finite number > 0 W/K, got {k_W_per_K:g}")
    s = load_scenario(scenario_file, list(overrides))
    if KINDS[s.kind].identify != "time":
        able = ", ".join(k.name for k in KINDS.values() if k.identify == "time")
        raise ScenarioError(scenario_file, ["kind"], f"--plan works on a rig scenario identified from a time history "
                                                     f"({able}): a sine of its amplitude and duration at each frequency")
    amplitude, duration = s.experiment.amplitude_m, s.experiment.duration_s
    d = 0.01                                                   # log10 k step of the sensitivity
    rows = []
    for f in frequencies:
        rate = max(20.0, 20.0 * f)
        t = np.linspace(0.0, duration, int(round(duration * rate)) + 1)
        z = amplitude * np.sin(2 * np.pi * f * t)
        fake = Measurements(Path(scenario_file), "time", t, {c: np.zeros_like(t) for c in noise}, z)
        model = RigModel(Path(scenario_file), tuple(overrides), fake)
        pred = model.predict([k_W_per_K, k_W_per_K * 10 ** d])
        info = {c: float(np.sum(((pred[c][1] - pred[c][0]) / d / noise[c]) ** 2)) for c in noise}
        total = sum(info.values())
        se_rel = math.log(10) / math.sqrt(total) if total > 0 else math.inf
        comps, p0 = model.components(())
        check = run_time_series(comps, k_W_per_K, sine_motion(amplitude, f), min(duration, 3.0 / f), 301, p0_Pa=p0)
        T = np.concatenate([pred[c][0] for c in pred if c.startswith("T_")] + [check.T_K.ravel()])
        mach = float(check.pipe_mach.max())
        valid = mach <= MAX_MACH and T_RANGE_K[0] <= T.min() and T.max() <= T_RANGE_K[1]
        rows.append({"frequency_Hz": f, "se_k_relative": se_rel, "pipe_mach_max": mach, "T_max_K": float(T.max()),
                     "valid": valid, **{f"information_share_{c}": v / total if total else 0 for c, v in info.items()}})
    return rows
