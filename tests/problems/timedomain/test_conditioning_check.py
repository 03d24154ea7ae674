"""The conditioning's removals checked by the diagnosis's one rule.

The conditioning on load removes a channel offset it estimates from part of the record; a short
pre-trigger under coloured noise, or a current transformer's remanence, can show one the record
does not have (held-out plant and motulator blind draws: every wrong name came from the
conditioning). The diagnosis refits its final model with the removal put back: an offset that
was there earns its place and is named, one that was not is not named."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.problems.timedomain.data import StartupDataset, StartupRecord, StopRecord
from benchmark.problems.timedomain.diagnosis.named import named_effects
from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings, diagnose
from tests.conftest import PAPER_MOTOR

NOISE_A = 0.05  # current noise, A
OFFSET_A = 0.06  # the offset on i_alpha, A: about one noise sigma, plain over a whole record


def _dataset(records, offset_in_record: float, offset_removed: float) -> StartupDataset:
    """The paper motor's start with noise, ``offset_in_record`` on i_alpha, and a conditioning
    that removed ``offset_removed`` from it (and says so)."""
    s, st = records["startup"], records["stop"]
    rng = np.random.default_rng(7)
    n = len(s["t"])
    rec = StartupRecord(
        t=s["t"], v_alpha=s["v_alpha"], v_beta=s["v_beta"],
        i_alpha=s["i_alpha"] + rng.normal(0, NOISE_A, n) + offset_in_record - offset_removed,
        i_beta=s["i_beta"] + rng.normal(0, NOISE_A, n), speed=s["speed"] + rng.normal(0, 0.2, n),
        removed={"sensor_offset": (0.0, 0.0, offset_removed, 0.0)})
    stop = StopRecord(t=st["t"], speed=st["speed"] + rng.normal(0, 0.2, len(st["t"])))
    return StartupDataset(pole_pairs=1, sample_time=1 / 12000, startups=[rec], stops=[stop], input_hold="zoh",
                          conditioning_removed=["sensor_offset"])


def _truth() -> dict[str, float]:
    return {k: getattr(PAPER_MOTOR, k) for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")}


@pytest.mark.parametrize("offset_in_record, named", [(OFFSET_A, True), (0.0, False)])
def test_an_offset_removal_is_named_only_where_the_record_has_the_offset(paper_records, offset_in_record, named):
    ds = _dataset(paper_records, offset_in_record, OFFSET_A)
    doc = diagnose(ds, _truth(), {}, DiagnosisSettings())
    first = doc["conditioning_check"][0]
    assert first["effect"] == "sensor_offset" and first["effects_beside"] == []
    # one noise sigma on one of three start-up channels: about a third on chi^2 per residual
    assert first["earns"] is named
    wrong, right = ((first["heldout_chi2_put_back"], first["heldout_chi2"]) if named
                    else (first["heldout_chi2"], first["heldout_chi2_put_back"]))
    assert right < 1.1 and wrong > 1.2, first
    assert first["excess_reduction"] > 0.9 if named else first["excess_reduction"] <= 0.0
    # and in sample, as every effect must (each fold's fit on its own samples: 1.05 and 0.0 here)
    assert first["in_sample_reduction"] > 0.9 if named else first["in_sample_reduction"] <= 0.0
    # the models stay fitted to the conditioned record: a removal of an offset the record does not
    # have leaves its bias there, and no candidate (none given) takes it: a gap, named by nothing
    assert doc["status"] == ("no_gap" if named else "unexplained")
    assert named_effects(doc) == (["sensor_offset"] if named else [])
    unnamed = [line for line in doc["conditioning"] if line.startswith("sensor_offset removed on load but not named")]
    assert len(unnamed) == (0 if named else 1)
    assert len(doc["conditioning_check"]) == 1
    # the check's refits are counted with the selection's fits (one tally per record)
    sel = doc["_models"]["selector"]
    assert [other.data.fits for other in sel.removal_fits.values()] == [sel.data.fits]
    assert doc["fits"]["to_convergence"] == sel.data.fits.by_cap[200][0] > 0
