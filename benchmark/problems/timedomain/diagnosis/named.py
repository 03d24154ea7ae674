"""What a diagnosis names: the one definition the blind evaluation and the calibration score.

A diagnosis names an effect in three ways: the selection chose it (``effects``), the
conditioning on load found and removed it and the rule kept the removal
(``removed_by_conditioning``: channel offsets, clipped or flattened current peaks;
:mod:`.conditioning_check`), or the base model holds it under another name and the document
says so (``held_by_base``: a constant load torque as Coulomb friction), the last only where the
data are accounted for (status ``no_gap`` or ``explained``: a load in the base's friction beside
a gap left unexplained is no diagnosis of a load). Every name counts, whatever the status: a
kept removal of an offset the record does not have names a wrong effect.
"""

from __future__ import annotations

from collections.abc import Mapping


def held_effects(doc: Mapping) -> list[str]:
    """The effects the base model holds under another name (``held_by_base``) that ``doc`` names:
    only with status ``no_gap`` or ``explained`` (module docstring)."""
    if doc["status"] not in ("no_gap", "explained"):
        return []
    return [h["effect"] for h in doc.get("held_by_base", [])]


def named_effects(doc: Mapping) -> list[str]:
    """Every effect ``doc`` (a ``diagnosis.json`` document, or a verdict with its keys
    ``status``, ``effects``, ``removed_by_conditioning``, ``held_by_base``) names, in order:
    the conditioning's, the chosen ones, then a load the base holds."""
    out: list[str] = []
    for e in [*doc.get("removed_by_conditioning", []), *doc.get("effects", []), *held_effects(doc)]:
        if e not in out:
            out.append(e)
    return out


def not_firm_effects(doc: Mapping) -> list[str]:
    """The chosen effects of ``doc`` that are not firm (``per_effect``'s ``firm``,
    :meth:`.rule.Rule.firm`): a noise estimate within its band would not have named them. An
    older document without ``firm`` has none."""
    return [pe["effect"] for pe in doc.get("per_effect") or [] if not pe.get("firm", True)]
