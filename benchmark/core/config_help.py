"""``--help`` of the Hydra entry points, written from their own configuration files.

Each entry point's help lists the keys of its primary configuration (``conf/<name>.yaml``), of the
problem and optimiser it would run (``problem.*``, ``optimizer.plugin.*``: the choices on the
command line are honoured) and the config groups with their options, each key with its default
and the first line of the comment that documents it in the YAML file. Internal hooks (anything
holding a ``_target_``) are left out, and so is every folder that is no group (``effect``: the
diagnosis's catalogue, chosen with ``effects=[...]``). Nothing here is written twice: a new key,
option or optimiser appears in the help once it is in ``conf/``.
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Sequence
from pathlib import Path

from benchmark.core.config_files import CONFIG_DIR, compose_config, config_groups

_KEY_LINE = re.compile(r"^(?P<indent> *)(?P<key>[A-Za-z_][\w]*):(?P<rest>.*)$")
#: Keys that describe a file, not a setting (a problem's ``name``, the data kind it reads).
_NOT_SETTINGS = ("name", "data_kind", "defaults", "hydra", "_target_", "_partial_")
WIDTH = 34
#: Longest line of a help text.
LINE = 110


def key_comments(path: Path) -> dict[str, str]:
    """``{dotted key: first sentence of its comment}`` of a YAML file: the comment block just
    above a key, else the comment on its own line."""
    out: dict[str, str] = {}
    block: list[str] = []
    parents: list[tuple[int, str]] = []
    for line in path.read_text(encoding="utf-8").splitlines():
        stripped = line.strip()
        if stripped.startswith("#"):
            block.append(stripped.lstrip("# "))
            continue
        m = _KEY_LINE.match(line)
        if not m:
            block = []
            continue
        indent, key, rest = len(m["indent"]), m["key"], m["rest"]
        parents = [(i, k) for i, k in parents if i < indent]
        dotted = ".".join([k for _, k in parents] + [key])
        parents.append((indent, key))
        inline = rest.split(" #", 1)[1].strip(" #") if " #" in rest else ""
        text = inline or " ".join(block)
        block = []
        if text:
            out[dotted] = text
    return out


def _first_sentence(text: str, limit: int) -> str:
    text = " ".join(text.split())
    cut = re.search(r"(?<=[a-z0-9)])\. (?=[A-Z(])", text)
    text = text[: cut.start() + 1] if cut else text
    if len(text) <= limit:
        return text
    return text[: text.rfind(" ", 0, limit - 4)].rstrip(" ,;:(") + " ..."


def _leaves(node, prefix: str = ""):
    """(dotted key, default) of a config's settings, hooks (``_target_``) and file facts left out."""
    from omegaconf import OmegaConf

    for key in node:
        if key in _NOT_SETTINGS:
            continue
        value = node._get_node(key)
        dotted = f"{prefix}{key}"
        if OmegaConf.is_dict(value):
            children = list(_leaves(value, dotted + "."))
            if "_target_" in value:  # a hook, or a plugin whose options are the other keys
                yield from children
                continue
            if children and len(value) > 0 and not _is_value_mapping(key):
                yield from children
                continue
        yield dotted, _show(value)


def _is_value_mapping(key: str) -> bool:
    # mappings that are one value ({name: [low, high]}, {effect: size}), not a block of settings
    return key in ("bounds", "effect_size", "effect_form", "weights", "held_friction")


def _defined_keys(path: Path) -> list[str]:
    """The dotted keys a YAML file sets itself (not those it inherits through its defaults list)."""
    import yaml

    def walk(doc, prefix=""):
        for k, v in doc.items():
            if k in ("defaults", "hydra"):
                continue
            if isinstance(v, dict) and v:
                yield from walk(v, f"{prefix}{k}.")
            else:
                yield f"{prefix}{k}"

    return list(walk(yaml.safe_load(path.read_text(encoding="utf-8")) or {}))


def _show(node) -> str:
    from omegaconf import OmegaConf

    if OmegaConf.is_config(node):
        return str(OmegaConf.to_container(node, resolve=False)).replace("'", "")
    value = node._value()
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    text = str(value)
    return text if len(text) <= 40 else text[:36] + " ..."


def _lines(keys, comments: dict[str, str], strip: str = "", where: str = "") -> list[str]:
    """One line per key with its default and comment; a block of :data:`BLOCK` or more keys under
    one mapping (``diagnosis.*``, ``optimizer.plugin.*``) as wrapped ``name=default`` pairs."""
    keys = list(keys)
    heads: dict[str, list] = {}
    for dotted, default in keys:
        heads.setdefault(dotted.rpartition(".")[0], []).append((dotted, default))
    out = []
    done: set[str] = set()
    for dotted, default in keys:
        head = dotted.rpartition(".")[0]
        if head and len(heads[head]) >= BLOCK:
            if head not in done:
                done.add(head)
                pairs = [f"{d.rpartition('.')[2]}={v}" for d, v in heads[head]]
                note = f" (each explained in {where})" if where else ""
                out += textwrap.wrap(f"{head}.{{{', '.join(pairs)}}}{note}", 108, initial_indent="  ",
                                     subsequent_indent="      ", break_on_hyphens=False)
            continue
        text = f"  {dotted}={default}"
        text = f"{text:<{WIDTH}} " if len(text) < WIDTH else f"{text}  "
        doc = _first_sentence(comments.get(dotted[len(strip):], ""), LINE - len(text))
        out.append((text + doc).rstrip() if len(doc) > 10 or not doc else text.rstrip())
    return out


#: A mapping with this many keys or more is listed compactly.
BLOCK = 6


def config_help(name: str, title: str, usage: Sequence[str], overrides: Sequence[str] = (),
                footer: Sequence[str] = (), sections: Sequence[str] = ("problem", "optimizer")) -> str:
    """The help text of the entry point whose primary configuration is ``conf/<name>.yaml``
    (with the keys of the groups in ``sections`` listed too)."""
    cfg = compose_config(name, [o for o in overrides if not o.startswith("hydra")])
    own = key_comments(CONFIG_DIR / f"{name}.yaml")
    defined = _defined_keys(CONFIG_DIR / f"{name}.yaml")
    groups = config_groups()
    in_config = [g for g in groups if g in cfg]
    lines = [title, "", "usage:", *(f"  {u}" for u in usage), "",
             f"Keys (key=value; defaults from conf/{name}.yaml):"]
    lines += _lines([(k, v) for k, v in _leaves(cfg) if k.split(".")[0] not in in_config
                     and any(k == d or k.startswith(d + ".") for d in defined)], own,
                    where=f"conf/{name}.yaml")
    for group in sections:
        if group not in cfg:
            continue
        choice = str(cfg[group].get("name", ""))
        path = CONFIG_DIR / group / f"{choice}.yaml"
        comments = key_comments(path) if path.is_file() else {}
        keys = list(_leaves(cfg[group], f"{group}."))
        if keys:
            lines += ["", f"Keys of {group}={choice} (conf/{group}/{choice}.yaml):"]
            lines += _lines(keys, comments, strip=f"{group}.", where=f"conf/{group}/{choice}.yaml")
    if in_config:
        lines += ["", "Config groups (group=option; * the default here):"]
        chosen_options = chosen(name, overrides)
        for g in in_config:
            opts = ", ".join(o + ("*" if o == chosen_options.get(g) else "") for o in groups[g])
            lines.append(f"  {g:<10} {opts}")
        presets = [g for g in groups if g not in cfg and all(
            "@package _global_" in (CONFIG_DIR / g / f"{o}.yaml").read_text(encoding="utf-8") for o in groups[g])]
        lines += [f"  +{g:<9} {', '.join(groups[g])}   (a preset, added with +{g}=OPTION)" for g in presets]
    lines += ["", "A nested key takes dots: problem.stator_resistance=prior; -m with a,b values sweeps.",
              "IMBENCH_DEBUG=1 shows tracebacks; --hydra-help shows Hydra's own flags."]
    return "\n".join([*lines, *footer]) + "\n"


def chosen(name: str, overrides: Sequence[str] = ()) -> dict[str, str]:
    """The option of each group a run of ``conf/<name>.yaml`` takes: the command line's, else the
    defaults list's (a default that follows another group, ``motor: ${problem}``, resolved)."""
    import yaml

    doc = yaml.safe_load((CONFIG_DIR / f"{name}.yaml").read_text(encoding="utf-8")) or {}
    out: dict[str, str] = {}
    for entry in doc.get("defaults", []):
        if isinstance(entry, dict):
            for k, v in entry.items():
                out[str(k).split(" ")[-1].lstrip("/")] = str(v)
        elif isinstance(entry, str) and entry not in out and entry != "_self_":
            out.update({g: v for g, v in chosen(entry).items() if g not in out})
    for o in overrides:
        key, _, value = o.lstrip("+").partition("=")
        if key in out or key in config_groups():
            out[key] = value
    for k, v in out.items():
        m = re.fullmatch(r"\$\{(\w+)\}", v)
        if m and m[1] in out:
            out[k] = out[m[1]]
    return out
