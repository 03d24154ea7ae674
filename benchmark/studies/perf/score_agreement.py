"""Agreement of the linearised score tests (:mod:`benchmark.problems.timedomain.diagnosis.score_tests`)
with the fitted screening, on the perf study's records.

Each record is diagnosed as usual (``python -m benchmark.diagnose``'s path, default
configuration, no figures); at every screening (single candidates, and pairs of the look-ahead)
the score tests of the same additions are computed from the same state (the current set's fit
on fold A, scored on fold B), timed, and kept beside the fitted screening's table. Per
screening: the rank correlation (Spearman) of the two orders, whether their best agree, and
how many of the screening's kept best (``screen_keep``) the score tests' as many best hold, and
whether the effect the round then chose is among them.

    python -m benchmark.studies.perf.score_agreement RECORDS_DIR OUT.json [only=a,b]
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import stats

from benchmark.problems.timedomain.diagnosis import selection
from benchmark.problems.timedomain.diagnosis.score_tests import score_tests


def screening_starts(selector, chosen):
    """The screening's starts of an addition (``Selector.starts_with(..., every=False)``, then
    ``Selector.profiled`` on fold A), as :func:`score_tests` takes them."""
    def starts(model, x, new):
        return selector.profiled(model, selector.starts_with(model, x, new, every=False), selector.masks["A"],
                                 range(len(chosen), len(model.effects)))
    return starts


def instrument(log: list) -> None:
    """Wrap :meth:`Selector.prescreen` so that each screening also runs the score tests."""
    original = selection.Selector.prescreen

    def prescreen(self, chosen, additions, cur, progress=None):
        t0 = time.process_time()
        scored = score_tests(self.model, list(chosen), cur.xs["A"], self.masks["A"], self.masks["B"], additions,
                             self.ctx, screening_starts(self, chosen))
        t_score = time.process_time() - t0
        t0 = time.process_time()
        kept, table = original(self, chosen, additions, cur, progress)
        log.append({"from": [e.name for e in chosen], "pairs": any(len(a) > 1 for a in additions),
                    "screening": table, "score_tests": scored, "cpu_score_tests_s": t_score,
                    "cpu_screening_s": time.process_time() - t0, "keep": self.settings.screen_keep})
        return kept, table

    selection.Selector.prescreen = prescreen


def _key(name: str) -> str:
    """An addition's name with a pair's members in a fixed order."""
    return "+".join(sorted(name.split("+")))


def agreement(entry: dict, chosen_next: str | None) -> dict:
    """Rank agreement of one screening with its score tests."""
    fitted = [_key(r["effect"]) for r in entry["screening"]]
    scored = [_key(r["effect"]) for r in entry["score_tests"]]
    chosen_next = _key(chosen_next) if chosen_next else None
    rank_f = {e: i for i, e in enumerate(fitted)}
    rank_s = {e: i for i, e in enumerate(scored)}
    common = [e for e in fitted if e in rank_s]
    rho = float(stats.spearmanr([rank_f[e] for e in common], [rank_s[e] for e in common])[0]) \
        if len(common) > 2 else float("nan")
    keep = min(entry["keep"], len(fitted))
    top_f, top_s = set(fitted[:keep]), set(scored[:keep])
    return {"from": entry["from"], "pairs": entry["pairs"], "n": len(common), "spearman": rho,
            "best_agrees": fitted[0] == scored[0], "kept_overlap": len(top_f & top_s), "keep": keep,
            "chosen_next": chosen_next, "chosen_in_score_top": (chosen_next in top_s) if chosen_next else None,
            "fitted_best": fitted[0], "scored_best": scored[0],
            "cpu_score_tests_s": entry["cpu_score_tests_s"], "cpu_screening_s": entry["cpu_screening_s"]}


def main(argv: list[str]) -> None:
    from benchmark.studies.perf.diagnosis_records import make_records

    opts = dict(a.split("=", 1) for a in argv[2:])
    names = opts["only"].split(",") if opts.get("only") else None
    out = {}
    for name, folder in make_records(Path(argv[0]), names):
        log: list = []
        instrument(log)
        doc = _diagnose(folder)
        selection.Selector.prescreen = _ORIGINAL
        rounds = [r for r in doc["selection"] if "candidates" in r]
        rows = []
        for entry in log:
            nxt = next((r.get("chosen") for r in rounds if r["from"] == entry["from"]
                        and bool(r.get("pairs")) == entry["pairs"]), None)
            rows.append(agreement(entry, nxt))
        out[name] = {"verdict": doc["verdict"], "screenings": rows, "raw": log}
        print(name, json.dumps([{k: r[k] for k in ("spearman", "best_agrees", "kept_overlap", "keep",
                                                   "chosen_in_score_top")} for r in rows]), flush=True)
    Path(argv[1]).write_text(json.dumps(out, indent=1, default=float) + "\n")


_ORIGINAL = selection.Selector.prescreen


def _diagnose(folder: Path) -> dict:
    from hydra import compose, initialize_config_dir

    from benchmark.core.harness import run_diagnosis
    from benchmark.studies.perf.common import CONF

    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        cfg = compose("diagnose", overrides=[f"data.path={folder}", "figures=false"])
    return run_diagnosis(cfg, Path(tempfile.mkdtemp(prefix="imbench-score-agreement-")))


if __name__ == "__main__":
    np.seterr(all="ignore")
    main(sys.argv[1:])
