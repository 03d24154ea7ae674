"""Edits of a data set's files in place, for the tests that make a valid set hostile."""

from pathlib import Path

import numpy as np

#: rad/s to rpm
RPM = 30 / np.pi


def lines(path: Path) -> list[str]:
    return path.read_text().split("\n")


def write_lines(path: Path, ls: list[str]) -> None:
    path.write_text("\n".join(ls))


def edit_cell(folder: Path, row: int, column: str, value: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    header = ls[0].split(",")
    cells = ls[row].split(",")
    cells[header.index(column)] = value
    ls[row] = ",".join(cells)
    write_lines(path, ls)


def edit_header(folder: Path, old: str, new: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    ls[0] = ",".join(new if c == old else c for c in ls[0].split(","))
    write_lines(path, ls)


def drop_column(folder: Path, column: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    k = ls[0].split(",").index(column)
    write_lines(
        path, [",".join(c for j, c in enumerate(line.split(",")) if j != k) if line else line for line in ls]
    )


def add_column(folder: Path, column: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    write_lines(path, [ls[0] + "," + column] + [line + ",20.5" if line else line for line in ls[1:]])


def scale_column(folder: Path, column: str, factor: float, name: str) -> None:
    path = folder / name
    ls = lines(path)
    k = ls[0].split(",").index(column)
    out = [ls[0]]
    for line in ls[1:]:
        if line:
            cells = line.split(",")
            cells[k] = repr(float(cells[k]) * factor)
            line = ",".join(cells)
        out.append(line)
    write_lines(path, out)


def set_meta(folder: Path, text: str) -> None:
    (folder / "meta.yaml").write_text(text)
