"""The original's file formats: ``out`` and ``min`` written, ``in`` and ``template`` read."""

from __future__ import annotations

import math
import re
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING

from plugins.genesis.settings import _LABELS, Gene, GenesisInputError, Settings, Template

if TYPE_CHECKING:
    from plugins.genesis.engine import SavedEntry


# The original's printf formats are kept verbatim (Python's % follows C printf for these).
_OUT_FORMAT = "%5d %5d %2d %2d %5.3f %.6e %.6e %.6e %.6e"
_MIN_COST_FORMAT = "  %11.4e "
_MIN_GEN_FORMAT = " %4d  %4d"


def format_out_line(gen, trials, lost, conv, bias, online, offline, best, avg) -> str:
    return _OUT_FORMAT % (
        gen,
        trials,
        lost,
        conv,
        bias,
        online,
        offline,
        best,
        avg,
    )


def format_min_lines(saved: list[SavedEntry], template: Template | None, gray: bool) -> list[str]:
    lines = []
    for e in saved:
        if template is not None:
            vals = template.decode(e.bits[None, :], gray)[0]
            head = "".join(g.format % v for g, v in zip(template.genes, vals.tolist(), strict=True))
        else:
            head = "".join(str(int(b)) for b in e.bits)
        lines.append(head + _MIN_COST_FORMAT % e.cost + _MIN_GEN_FORMAT % (e.gen, e.trial))
    return lines


def write_out(path, lines: list[str]) -> None:
    Path(path).write_text("".join(line + "\n" for line in lines))


def write_min(path, saved: list[SavedEntry], template: Template | None, gray: bool) -> None:
    Path(path).write_text("".join(line + "\n" for line in format_min_lines(saved, template, gray)))


def _read_lines(path) -> list[str]:
    try:
        return Path(path).read_text().splitlines()
    except OSError as exc:
        raise GenesisInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise GenesisInputError(f"{path}: not a text file") from None


def read_settings(path) -> tuple[Settings, dict[str, int]]:
    """Read an ``in`` file (16 ``Label = value`` lines). Returns the settings and the line number
    of each field (for messages)."""
    lines = _read_lines(path)
    values: dict = {}
    where: dict[str, int] = {}
    fl = list(fields(Settings))
    n = 0
    for f in fl:
        label = _LABELS[f.name]
        while n < len(lines) and not lines[n].strip():
            n += 1
        if n >= len(lines):
            raise GenesisInputError(f"{path}: line {n + 1}: missing '{label} = ...' (file ends early)")
        text = lines[n]
        n += 1
        left, eq, right = text.partition("=")
        if not eq or " ".join(left.split()).lower() != label.lower():
            raise GenesisInputError(f"{path}: line {n}: expected '{label} = ...', got {text.strip()!r}")
        right = right.strip()
        kind = f.type if isinstance(f.type, str) else f.type.__name__
        try:
            if kind == "int":
                val = int(right)
            elif kind == "float":
                val = float(right)
                if not math.isfinite(val):
                    raise ValueError
            else:
                if not right or len(right.split()) != 1:
                    raise ValueError
                val = right
        except ValueError:
            want = {"int": "an integer", "float": "a number"}.get(kind, "one word of option letters")
            raise GenesisInputError(f"{path}: line {n}: {label}: expected {want}, got {right!r}") from None
        values[f.name] = val
        where[f.name] = n
    settings = Settings(**values)
    bad = settings.check()
    if bad:
        name, msg = bad[0]
        raise GenesisInputError(f"{path}: line {where[name]}: {_LABELS[name]}: {msg}")
    return settings, where


_FMT_RE = re.compile(r"^[^%]*%[-+ #0]*\d*(?:\.\d+)?[lL]?[eEfFgG][^%]*$")


def read_template(path) -> Template:
    """Read a ``template`` file: ``genes: n`` then per gene ``gene k``, ``min:``, ``max:``,
    ``values:``, ``format:`` lines (blank lines ignored)."""
    raw = _read_lines(path)
    lines = [(k + 1, t.strip()) for k, t in enumerate(raw) if t.strip()]
    pos = 0

    def take(key: str):
        nonlocal pos
        if pos >= len(lines):
            raise GenesisInputError(f"{path}: line {len(raw) + 1}: missing '{key}' (file ends early)")
        no, text = lines[pos]
        pos += 1
        k, colon, v = text.partition(":")
        if key == "gene":
            if text.split()[0].lower() != "gene":
                raise GenesisInputError(f"{path}: line {no}: expected 'gene <k>', got {text!r}")
            return no, text
        if not colon or k.strip().lower() != key:
            raise GenesisInputError(f"{path}: line {no}: expected '{key}: ...', got {text!r}")
        return no, v.strip()

    no, v = take("genes")
    try:
        n_genes = int(v)
        if n_genes < 1:
            raise ValueError
    except ValueError:
        raise GenesisInputError(f"{path}: line {no}: genes: expected a positive integer, got {v!r}") from None
    genes = []
    for _ in range(n_genes):
        take("gene")
        nums = []
        for key in ("min", "max"):
            no, v = take(key)
            try:
                x = float(v)
                if not math.isfinite(x):
                    raise ValueError
            except ValueError:
                raise GenesisInputError(f"{path}: line {no}: {key}: expected a number, got {v!r}") from None
            nums.append(x)
        no, v = take("values")
        try:
            values = int(v)
            if values < 2 or values & (values - 1):
                raise ValueError
        except ValueError:
            raise GenesisInputError(f"{path}: line {no}: values: expected a power of two >= 2, got {v!r}") from None
        no, fmt = take("format")
        fmt = re.sub(r"%([-+ #0]*\d*(?:\.\d+)?)[lL]", r"%\1", fmt)
        if not _FMT_RE.match(fmt):
            raise GenesisInputError(
                f"{path}: line {no}: format: expected one printf float conversion such as %7.2f, got {fmt!r}"
            )
        genes.append(Gene(nums[0], nums[1], values, fmt))
    if pos < len(lines):
        no, text = lines[pos]
        raise GenesisInputError(f"{path}: line {no}: unexpected text after {n_genes} genes: {text!r}")
    return Template(genes)
