#!/usr/bin/env python3
"""Points every citation of MODEL.md at docs/model.md.

Run from anywhere inside a wetgran checkout:

    python3 scripts/cite_model_doc.py            # rewrite the files
    python3 scripts/cite_model_doc.py --dry-run  # only count

In every git-tracked *.rs, *.md, *.toml and *.sh file of the repository, each occurrence of the
file name MODEL.md becomes docs/model.md, so "MODEL.md 7" reads "docs/model.md 7",
"(MODEL.md 4.2)" reads "(docs/model.md 4.2)" and "MODEL.md's" reads "docs/model.md's"; section
numbers and the surrounding text stay as they are. docs/model.md itself and this script are left
alone. An occurrence that is part of a longer path or name (".../MODEL.md", "XMODEL.md",
"MODEL.mdx") is not a citation of the document and is left alone; those are listed at the end.

Prints the number of replacements per file and in all, then the .rs lines that the longer name
pushes beyond 100 characters (comments, which rustfmt leaves as they are; rewrap them by hand if
wanted). Exit status 0, or 1 when occurrences of MODEL.md remain. Python 3.8 or newer, no
dependencies.
"""

import argparse
import re
import subprocess
import sys
from pathlib import Path

SUFFIXES = (".rs", ".md", ".toml", ".sh")
SKIP = {"docs/model.md", "scripts/cite_model_doc.py"}
OLD = "MODEL.md"
NEW = "docs/model.md"
# The name on its own: not inside a path, a longer word or a longer extension.
CITATION = re.compile(r"(?<![\w/.-])MODEL\.md(?![\w-])")
WIDTH = 100


def tracked_files(root):
    out = subprocess.run(
        ["git", "-C", str(root), "ls-files", "-z"],
        check=True,
        stdout=subprocess.PIPE,
    ).stdout
    return [p for p in out.decode("utf-8").split("\0") if p]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dry-run", action="store_true", help="count, do not write")
    args = parser.parse_args()

    root = Path(
        subprocess.run(
            ["git", "rev-parse", "--show-toplevel"],
            check=True,
            stdout=subprocess.PIPE,
        )
        .stdout.decode("utf-8")
        .strip()
    )

    total = 0
    long_lines = []
    leftovers = []
    for rel in tracked_files(root):
        if rel in SKIP or not rel.endswith(SUFFIXES):
            continue
        path = root / rel
        if not path.is_file():
            continue
        text = path.read_bytes().decode("utf-8")
        new_text, count = CITATION.subn(NEW, text)
        if count:
            total += count
            print(f"{count:4d}  {rel}")
            if rel.endswith(".rs"):
                for number, line in enumerate(new_text.split("\n"), start=1):
                    if NEW in line and len(line) > WIDTH:
                        long_lines.append(f"{rel}:{number}: {len(line)} characters")
            if not args.dry_run:
                path.write_bytes(new_text.encode("utf-8"))
        for number, line in enumerate(new_text.split("\n"), start=1):
            if OLD in line:
                leftovers.append(f"{rel}:{number}: {line.strip()}")

    verb = "would be replaced" if args.dry_run else "replaced"
    print(f"{total:4d}  in all ({verb})")
    if long_lines:
        print(f"\nlines of .rs files now longer than {WIDTH} characters:")
        for entry in long_lines:
            print(f"  {entry}")
    if leftovers:
        print(f"\n{OLD} left alone (part of a longer path or name):")
        for entry in leftovers:
            print(f"  {entry}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
