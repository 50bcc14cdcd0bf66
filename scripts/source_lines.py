#!/usr/bin/env python3
"""Counts the lines of every crate's src/ the way issue 34 measures them.

Per crate: all lines (`wc -l`), and split into code, comment (`//` lines, doc comments
included), blank, and unit-test lines (from a `#[cfg(test)]` line to the end of its file,
which is where this project keeps its unit tests). Run from the repository root.
"""
import os
import sys

CRATES = [
    ("wetgran", "src"),
    ("wetgran-core", "crates/core/src"),
    ("wetgran-bench", "crates/bench/src"),
    ("wetgran-testkit", "crates/testkit/src"),
]


def count(root):
    tally = {"code": 0, "comment": 0, "blank": 0, "test": 0}
    files = 0
    for folder, _, names in os.walk(root):
        for name in names:
            if not name.endswith(".rs"):
                continue
            files += 1
            in_tests = False
            with open(os.path.join(folder, name), encoding="utf-8") as text:
                for line in text:
                    stripped = line.strip()
                    if stripped.startswith("#[cfg(test)]"):
                        in_tests = True
                    if in_tests:
                        tally["test"] += 1
                    elif not stripped:
                        tally["blank"] += 1
                    elif stripped.startswith("//"):
                        tally["comment"] += 1
                    else:
                        tally["code"] += 1
    return files, tally


def main():
    total = {"files": 0, "all": 0, "code": 0, "comment": 0, "blank": 0, "test": 0}
    print(f"{'crate':<16} {'files':>5} {'all':>7} {'code':>7} {'comment':>8} {'blank':>6} {'test':>6}")
    for crate, root in CRATES:
        if not os.path.isdir(root):
            sys.exit(f"{root} not found: run from the repository root")
        files, tally = count(root)
        lines = sum(tally.values())
        row = {"files": files, "all": lines, **tally}
        for key in total:
            total[key] += row[key]
        print(f"{crate:<16} {files:>5} {lines:>7} {tally['code']:>7} {tally['comment']:>8} "
              f"{tally['blank']:>6} {tally['test']:>6}")
    print(f"{'total':<16} {total['files']:>5} {total['all']:>7} {total['code']:>7} "
          f"{total['comment']:>8} {total['blank']:>6} {total['test']:>6}")


if __name__ == "__main__":
    main()
