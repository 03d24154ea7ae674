"""The diagnosis evaluated blind, per data source.

``python -m benchmark.blind source=own|plant|motulator n=... seed=...`` (time domain) and
``python -m benchmark.blind_admittance`` (slip sweep) make ``n`` data sets, each with a drawn
set of effects (none, one or two), write each to a folder, move its ``truth.yaml`` to a
separate folder before the diagnosis is given the data folder, and compare the verdicts with
the truth afterwards. Sources:

* ``own``: the project's synthetic plant (:mod:`synthetic.timedomain`) with the effects of
  ``conf/effect/`` (sizes log-uniform in their realistic ranges, forms from each effect's
  ``random_form``), a motor spread around the preset, Gaussian noise;
* ``plant``: the independent flux-linkage plant (:mod:`synthetic.independent`), which draws
  its own motors, scenarios, effect sizes and forms and non-Gaussian noise;
* ``motulator``: the third-party simulator (:mod:`synthetic.motulator_source`; effects
  ``main_saturation``, ``two_mass``, ``load_torque``).

Forms (``forms=development|heldout|all``, default ``development``): the independent plant and
motulator draw their effects' forms from the development forms (those the diagnosis was
developed on, the behaviour before the split), the held-out forms (second physical forms,
for the final scoring only) or both; the split is :mod:`synthetic.independent.forms`
(``docs/effect_forms.md``). The own plant's forms are the diagnosis's own: it has no held-out
forms, and ``forms=heldout`` is refused for it.

Scores (:func:`summarise`): a verdict counts right when its effect set equals the injected
set (``none`` for an effect-free set; an extra name is a miss; ``unexplained`` names no
effect), whatever its status; with Wilson 95 % intervals. False alarms: effect-free sets
whose status is not ``no_gap`` or that name an effect anyway. Two-effect sets: both injected effects
named. An injected effect the conditioning removed and named (offsets, clipped or flattened
currents) counts as found; an effect the document says the base model holds (``held_by_base``: a
constant load torque taken as Coulomb friction) counts as named, injected or not. Injected
effects the base model cannot see (its held-out gap within the noise band) are left out and listed;
in a two-effect set, each effect's own gap is measured on the set made again with it alone, and one
within the band that the verdict does not name is left out of that set's score.
"""

from __future__ import annotations

import copy
import json
import math
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from omegaconf import DictConfig, OmegaConf, open_dict

from benchmark.analysis.blind_report import render, summarise, wilson  # noqa: F401  (re-exported)
from benchmark.core.effects import load_effects
from benchmark.core.io import write_text_atomic, write_yaml_atomic
from benchmark.problems.timedomain.diagnosis.named import held_effects, named_effects, not_firm_effects

MOTOR_KEYS = ("Rs", "Ls", "Le", "Rr", "J", "fv")
#: Effects a time-domain base model of case 2 already holds (never an injected "effect").
IN_BASE = {2: ("coulomb_friction",), 1: ()}


def _float_or_none(v) -> float | None:  # noqa: D103
    return None if v is None else float(v)


def _form_set(v) -> str:
    """The ``forms`` key: ``development`` (default), ``heldout`` or ``all``."""
    from synthetic.independent.forms import FORM_SETS

    v = "development" if v is None else str(v)
    if v not in FORM_SETS:
        from benchmark.core.errors import ConfigError

        raise ConfigError(f"forms: one of {list(FORM_SETS)}, got {v!r}")
    return v


@dataclass(frozen=True)
class BlindSettings:
    """What a blind evaluation draws, where it works and what it writes; made once from the
    composed configuration (``conf/blind.yaml``, ``conf/blind_admittance.yaml``) by
    :meth:`from_run` in the entry points.

    Attributes
    ----------
    source : ``own``, ``plant`` or ``motulator`` (time domain; unused by the slip sweep).
    n : number of data sets.
    seed : master seed of the draws; each set gets its own stream spawned from it.
    free_share : share of effect-free sets (the first ones), or None: each set is effect-free
        with the weight of one effect among the drawn outcomes (the slip sweep).
    two_share : share of the other sets that carry two effects at once (with ``free_share``).
    vary_form : vary each injected effect's form (the effect's own :meth:`random_form`).
    forms : the form set of the plant and motulator sources (``development``, ``heldout``,
        ``all``; see the module docstring).
    vary_motor : relative spread of the motor's parameters, each scaled by exp(U(-v, v)).
    exclude_effects : effects never injected.
    only_effects : if not empty, the only effects injected (the others are never drawn).
    cycle_effects : single-effect sets take the effects in turn (set ``j`` of them the
        ``j mod m``-th of the ``m`` allowed, in name order), so that each effect gets its share
        of the sets instead of a random count (the per-effect tallies of new effects).
    base_case : the diagnosis's time-domain base model case (``diagnosis.base_case``; 2 holds
        Coulomb friction, which is then never injected), None when the config has none.
    workdir : folder of the data sets (``sets/``), their truth (``truth/``) and the diagnoses.
    out : folder of the scores (``confusion.md``, ``blind.json``, ``config.yaml``).
    resume, report_only : (time domain) reuse the rows of sets already diagnosed in ``workdir``;
        score only those (an interrupted run).
    duration, sample_rate, rated_power, motulator_stop : the motulator source's start-up (s),
        sampling rate (Hz), rated power (W; load-torque sizes are fractions of rated torque) and
        whether it also records a stop (None: not configured).
    motulator_motors : the motulator source's motors, one drawn per set: ``preset`` (the run's
        motor) and zoo motor names (``motulator_2p2kw``: motulator's own 2.2 kW example machine).
    plant_duration, plant_stop : the plant source's start-up (s; None: the plant's own draw) and
        whether it also records a stop.
    tuned_on : one line on what the diagnosis's thresholds were tuned on, for the report.
    diagnosis_seed : the seed each diagnosis runs with (its base identification's), or None:
        the draw's ``seed``. The same sets diagnosed with another seed show which verdicts hang
        on where the local fits end.
    pair_visibility : (time domain) measure each effect of a two-effect set alone
        (:func:`~benchmark.analysis.blind_sources.effect_alone_gaps`); one within the noise band
        that the verdict does not name is left out of that set's score, as an invisible single
        effect is.
    run : the composed configuration (plain, resolved); each set's generator and diagnosis
        configurations are copies of it (:func:`generator_config`, :func:`diagnosis_config`),
        and it is written next to the scores.
    """

    n: int
    seed: int
    workdir: Path
    out: Path
    source: str = "own"
    free_share: float | None = None
    two_share: float = 0.0
    vary_form: bool = True
    forms: str = "development"
    vary_motor: float = 0.0
    exclude_effects: tuple[str, ...] = ()
    only_effects: tuple[str, ...] = ()
    cycle_effects: bool = False
    base_case: int | None = None
    resume: bool = True
    report_only: bool = False
    duration: float | None = None
    sample_rate: float | None = None
    rated_power: float | None = None
    motulator_stop: bool = True
    motulator_motors: tuple[str, ...] = ("preset",)
    plant_duration: float | None = None
    plant_stop: bool = True
    tuned_on: str = ""
    diagnosis_seed: int | None = None
    pair_visibility: bool = True
    run: Mapping = field(default_factory=dict, repr=False)

    @classmethod
    def from_run(cls, run: Mapping) -> BlindSettings:
        """The settings of a composed configuration (a plain mapping or a DictConfig)."""
        if isinstance(run, DictConfig):
            run = OmegaConf.to_container(run, resolve=True)
        diagnosis = run.get("diagnosis") or {}
        return cls(
            n=int(run["n"]), seed=int(run["seed"]), workdir=Path(run["workdir"]), out=Path(run["out"]),
            source=str(run.get("source", "own")), free_share=_float_or_none(run.get("free_share")),
            two_share=float(run.get("two_share") or 0.0),
            vary_form=bool(run.get("vary_form", True)), forms=_form_set(run.get("forms")),
            vary_motor=float(run.get("vary_motor") or 0.0),
            exclude_effects=tuple(str(e) for e in run.get("exclude_effects") or ()),
            only_effects=tuple(str(e) for e in run.get("only_effects") or ()),
            cycle_effects=bool(run.get("cycle_effects") or False),
            base_case=None if diagnosis.get("base_case") is None else int(diagnosis["base_case"]),
            resume=bool(run.get("resume", True)), report_only=bool(run.get("report_only") or False),
            duration=_float_or_none(run.get("duration")), sample_rate=_float_or_none(run.get("sample_rate")),
            rated_power=_float_or_none(run.get("rated_power")), motulator_stop=bool(run.get("motulator_stop", True)),
            motulator_motors=tuple(str(m) for m in run.get("motulator_motors") or ("preset",)),
            plant_duration=_float_or_none(run.get("plant_duration") or None),
            plant_stop=bool(run.get("plant_stop", True)), tuned_on=str(run.get("tuned_on", "")),
            pair_visibility=bool(run.get("pair_visibility", True)),
            diagnosis_seed=None if run.get("diagnosis_seed") is None else int(run["diagnosis_seed"]),
            run=copy.deepcopy(dict(run)))

    @property
    def in_base(self) -> tuple[str, ...]:
        """Effects the diagnosis's base model already holds (never injected)."""
        return IN_BASE.get(self.base_case, ())

    def may_inject(self, name: str) -> bool:
        """Whether effect ``name`` may be drawn (not excluded; in ``only_effects`` when given)."""
        return name not in self.exclude_effects and (not self.only_effects or name in self.only_effects)


def n_effects_of(i: int, settings: BlindSettings) -> int:
    """Effect count of set ``i``: every ``1/free_share``-th set is effect-free, a share
    ``two_share`` of the others carry two effects (deterministic, so that each count is met)."""
    n = int(settings.n)
    n_free = int(round(float(settings.free_share) * n))
    if i < n_free:
        return 0
    n_two = int(round(float(settings.two_share) * (n - n_free)))
    return 2 if i - n_free < n_two else 1


def cycled(i: int, settings: BlindSettings, pool: list[str]) -> str:
    """The effect of single-effect set ``i`` when ``settings.cycle_effects``: the effects of
    ``pool`` in turn, counted from the first set with effects."""
    n_free = int(round(float(settings.free_share or 0.0) * int(settings.n)))
    return pool[(i - n_free) % len(pool)]


def draw_sets(settings: BlindSettings, problem: str = "timedomain", motor_keys=MOTOR_KEYS, exclude=()) -> list[dict]:
    """The ``own`` draws: effects (none, one or two), sizes, forms (each effect's own
    :meth:`~benchmark.core.effects.Effect.random_form`), motor spread, noise seed.

    Each set has its own random stream (spawned from ``settings.seed``), so a set's draw does not
    depend on how many sets come before it."""
    effects = load_effects(problem)
    names = sorted(n for n in effects if n not in exclude and settings.may_inject(n))
    seeds = np.random.SeedSequence(settings.seed).spawn(settings.n)
    draws = []
    for i, ss in enumerate(seeds):
        rng = np.random.default_rng(ss)
        if settings.free_share is not None:
            k = n_effects_of(i, settings)
        else:
            k = int(rng.random() >= 1.0 / (1 + len(names)))
        chosen = sorted(str(e) for e in rng.choice(names, size=k, replace=False)) if k else []
        if settings.cycle_effects and k == 1:
            chosen = [cycled(i, settings, names)]
        d = {"index": i, "effects": chosen, "noise_seed": int(rng.integers(2**31 - 1))}
        spread = settings.vary_motor
        d["motor_scale"] = {m: float(np.exp(rng.uniform(-spread, spread))) for m in motor_keys}
        d["size"], d["form"] = {}, {}
        for e in chosen:
            lo, hi = effects[e].realistic
            d["size"][e] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            if settings.vary_form:
                d["form"][e] = effects[e].random_form(rng)
        d["effect"] = "+".join(chosen) or "none"  # the single-effect label of older callers
        draws.append(d)
    return draws


def _run_copy(settings: BlindSettings) -> DictConfig:
    return OmegaConf.create(copy.deepcopy(dict(settings.run)))


def generator_config(settings: BlindSettings, d: dict, scale_motor=None, no_effect: list | None = None) -> DictConfig:
    """The configuration the synthetic generator gets for draw ``d``: a copy of the composed
    configuration with the draw's motor spread (``scale_motor(parameters, motor_scale)``, default:
    each parameter times its factor), noise seed, effects (``no_effect`` when there are none),
    sizes and forms, and no data folder."""
    c = _run_copy(settings)
    with open_dict(c):
        if scale_motor is None:
            for k, s in d["motor_scale"].items():
                c.motor.parameters[k] = float(c.motor.parameters[k]) * s
        else:
            scale_motor(c.motor.parameters, d["motor_scale"])
        c.noise.seed = d["noise_seed"]
        c.effects = list(d["effects"]) or list(no_effect or [])
        c.effect_size = dict(d["size"])
        c.effect_form = {k: dict(v) for k, v in d["form"].items()}
        c.data.path = None
    return c


def diagnosis_config(settings: BlindSettings, folder: Path) -> DictConfig:
    """The configuration the diagnosis gets for a data folder: a copy of the composed
    configuration pointed at ``folder``, with no effects of its own and no figures; its
    ``seed`` (the base identification's) is ``settings.diagnosis_seed`` when given, else the
    draw's."""
    c = _run_copy(settings)
    with open_dict(c):
        c.data.path = str(folder)
        if settings.diagnosis_seed is not None:
            c.seed = int(settings.diagnosis_seed)
        c.effects, c.effect_size, c.effect_form = [], {}, {}
        c.figures = False
    return c


def label_of(effects) -> str:
    return "+".join(sorted(effects)) or "none"


def predicted_label(doc: dict) -> str:
    return {"no_gap": "none", "unexplained": "unexplained"}.get(doc["status"]) or label_of(doc["effects"])


def diagnose_folder(settings: BlindSettings, folder: Path, outdir: Path) -> dict:
    """The diagnosis of a data folder (its truth already moved away)."""
    from benchmark.core.harness import run_diagnosis

    return run_diagnosis(diagnosis_config(settings, folder), outdir)


def make_set(d: dict, make, work: Path) -> Path:
    """Make set ``d`` into ``work/sets/set_NNN`` (``make(d, folder)``) and move its ``truth.yaml``
    to ``work/truth`` (if it has one); the data folder."""
    name = f"set_{d['index']:03d}"
    folder = work / "sets" / name
    if folder.exists():
        shutil.rmtree(folder)
    make(d, folder)
    # the truth leaves the data folder before the diagnosis sees it
    (work / "truth").mkdir(parents=True, exist_ok=True)
    if (folder / "truth.yaml").exists():
        (folder / "truth.yaml").replace(work / "truth" / f"{name}.yaml")
    return folder


def make_and_diagnose(settings: BlindSettings, d: dict, make, work: Path) -> dict:
    """Make set ``d`` (:func:`make_set`), then diagnose its folder; the diagnosis document."""
    folder = make_set(d, make, work)
    return diagnose_folder(settings, folder, work / "diagnoses" / folder.name)


def failed_row(index: int, effects: list, stage: str, error: BaseException) -> dict:
    """The row of a set whose making (``stage`` ``make``) or diagnosis (``diagnose``) raised
    ``error``: kept with its message so that the draw goes on. A diagnosis that raised is a
    miss of every score it enters (its verdict names nothing, ``predicted`` is ``error``); a
    set the source could not make is left out of the scores and listed
    (:func:`~benchmark.analysis.blind_report.summarise`)."""
    label = label_of(effects)
    return {"index": index, "truth": label, "truth_effects": list(effects), "injected": label,
            "left_out_effects": [], "predicted": "error", "status": "error",
            "verdict": f"{stage} raised {type(error).__name__}: {error}", "error_stage": stage,
            "effects": [], "conditioned": [], "held_by_base": [], "not_firm": [], "explained_share": math.nan,
            "gap_before": math.nan, "gap_after": math.nan, "invisible": False}


def make_and_diagnose_or_fail(settings: BlindSettings, d: dict, make, work: Path) -> dict:
    """The scored row of set ``d``: :func:`make_and_diagnose`, or :func:`failed_row` when the
    making or the diagnosis raised (its traceback in ``work/diagnoses/set_NNN/error.txt``)."""
    import traceback

    stage, outdir = "make", work / "diagnoses" / f"set_{d['index']:03d}"
    try:
        folder = make_set(d, make, work)
        stage = "diagnose"
        doc = diagnose_folder(settings, folder, outdir)
    except Exception as error:  # any failure of one set is that set's row
        outdir.mkdir(parents=True, exist_ok=True)
        write_text_atomic(outdir / "error.txt", traceback.format_exc())
        return failed_row(d["index"], d["effects"], stage, error) | {"wall_time_s": math.nan}
    return score_row(d["index"], d["effects"], doc) | {"indistinguishable": doc.get("indistinguishable", []),
                                                        "wall_time_s": float(doc.get("wall_time_s", math.nan))}


def score_row(index: int, effects: list, doc: dict, alone_no_gap=()) -> dict:
    """One scored row: the injected ``effects`` against every effect the diagnosis document
    ``doc`` names (:func:`~benchmark.problems.timedomain.diagnosis.named.named_effects`: chosen,
    found and removed by the conditioning, or held by the base where the data are accounted for).
    A verdict that names nothing reads ``none`` (no gap) or ``unexplained``.

    ``alone_no_gap``: effects of a two-effect set whose own base-model gap (the set made with that
    effect alone, :func:`effect_alone_gaps`) is within the noise band. One the verdict does not name
    is left out of the set's score (``left_out_effects``), as a single effect the base model cannot
    see is; the set is then scored on the other one. ``injected`` keeps the whole set. A set is
    left out as invisible only when its base is at the noise level and the diagnosis names nothing."""
    named = named_effects(doc)
    left = [e for e in effects if e in alone_no_gap and e not in named]
    injected, effects = list(effects), [e for e in effects if e not in left] if len(left) < len(effects) else effects
    left = [e for e in injected if e not in effects]
    return {"index": index, "truth": label_of(effects), "truth_effects": list(effects),
            "injected": label_of(injected), "left_out_effects": left,
            "predicted": label_of(named) if named else predicted_label(doc), "status": doc["status"],
            "verdict": doc["verdict"], "effects": named,
            "conditioned": list(doc.get("removed_by_conditioning", [])), "held_by_base": held_effects(doc),
            "not_firm": not_firm_effects(doc),
            "explained_share": float(doc["explained_share"]),
            "gap_before": float(doc["gap_before"]["heldout_rms_over_noise"]),
            "gap_after": float(doc["gap_after"]["heldout_rms_over_noise"]),
            "invisible": bool(effects) and doc["status"] == "no_gap" and not named,
            "warnings": list(doc.get("warnings", []))}


def write_scores(settings: BlindSettings, rows: list[dict], out: Path, command: str, title: str) -> dict:
    """Summarise ``rows`` and write ``confusion.md``, ``blind.json`` and ``config.yaml`` to ``out``."""
    summary = summarise(rows)
    out.mkdir(parents=True, exist_ok=True)
    text = render(summary, rows, command, title, settings.tuned_on)
    write_text_atomic(out / "confusion.md", text)
    doc = {"summary": summary, "sets": rows}
    write_text_atomic(out / "blind.json", json.dumps(doc, indent=1, default=float) + "\n")
    write_yaml_atomic(out / "config.yaml", copy.deepcopy(dict(settings.run)))
    print(text)
    return summary


def run_source(settings: BlindSettings, command: str) -> dict:
    """Make, hide the truth of, and diagnose every set of ``settings.source``; write the scores
    to ``settings.out/<source>``."""
    from benchmark.analysis.blind_sources import SOURCES, effect_alone_gaps

    source = settings.source
    if source not in SOURCES:
        from benchmark.core.errors import ConfigError

        raise ConfigError(f"source: one of {sorted(SOURCES)}, got {source!r}")
    from benchmark.problems.timedomain.diagnosis.run import diagnosis_settings

    diagnosis_settings(settings.run)  # a mistyped diagnosis.* key stops here, not as a failed row per set
    draws, make = SOURCES[source](settings)
    work = settings.workdir / source
    rows = []
    results_file = work / "rows.jsonl"
    done = {}
    if results_file.exists() and settings.resume:
        for line in results_file.read_text().splitlines():
            r = json.loads(line)
            if r.get("status") == "error":  # a set that raised is made and diagnosed again
                done.pop(r["index"], None)
            else:
                done[r["index"]] = r
    work.mkdir(parents=True, exist_ok=True)
    if settings.report_only:  # score the sets diagnosed so far (an interrupted run)
        draws = [d for d in draws if d["index"] in done]
    for d in draws:
        if d["index"] in done:  # scored again from its diagnosis: the rules of this code
            row = done[d["index"]]
            doc_file = work / "diagnoses" / f"set_{d['index']:03d}" / "diagnosis.json"
            if doc_file.exists():
                row = row | score_row(d["index"], d["effects"], json.loads(doc_file.read_text()))
        else:
            row = make_and_diagnose_or_fail(settings, d, make, work)
            row["draw"] = {k: v for k, v in d.items() if k not in ("spec",)}
            with open(results_file, "a") as fh:
                fh.write(json.dumps(row, default=float) + "\n")
        if settings.pair_visibility and len(d["effects"]) == 2 and row["status"] != "error":
            alone = effect_alone_gaps(settings, d, make, work)
            doc = json.loads((work / "diagnoses" / f"set_{d['index']:03d}" / "diagnosis.json").read_text())
            row = row | score_row(d["index"], d["effects"], doc, [e for e, a in alone.items() if a["no_gap"]])
            row["alone_gaps"] = {e: a["gap"] for e, a in alone.items()}
        rows.append(row)
        if d["index"] in done:
            continue
        print(f"[{source}] set {d['index']:3d}: truth {row.get('injected', row['truth']):<40} -> {row['status']:<16} "
              f"{row['verdict']:<40} "
              f"gap {row['gap_before']:.2f} -> {row['gap_after']:.2f} ({row['wall_time_s']:.0f} s)", flush=True)
    title = f"# Blind evaluation of the time-domain diagnosis: source `{source}`"
    return write_scores(settings, rows, settings.out / source, command, title)


# -- the slip-sweep evaluation (single effect per set) -------------------------------------
def run_blind(settings: BlindSettings, draws: list[dict], set_config, generate, title: str, command: str) -> dict:
    """Make, hide the truth of, and diagnose every drawn set of a synthetic generator
    (``set_config(settings, draw)`` -> its configuration, ``generate(config, folder)``); write
    the scores to ``settings.out``."""
    rows = []
    for d in draws:
        doc = make_and_diagnose(settings, d, lambda d, folder: generate(set_config(settings, d), folder),
                                settings.workdir)
        effects = [] if d["effect"] == "none" else d["effect"].split("+")
        row = score_row(d["index"], effects, doc) | {"wall_time_s": float(doc.get("wall_time_s", math.nan))}
        rows.append(row)
        print(f"set {d['index']:3d}: truth {row['truth']:<20} verdict {row['verdict']:<20} ({row['status']}) "
              f"gap {row['gap_before']:.2f} -> {row['gap_after']:.2f}", flush=True)
    return write_scores(settings, rows, settings.out, command, title)
