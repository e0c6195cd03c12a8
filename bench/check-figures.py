#!/usr/bin/env python3
"""Checks that the figures the documents quote are in the documents and in their
raw files. bench/figures.txt holds one check a line, in either of two forms:

    DOC | FIGURE | RAW_FILE | PATTERN
    DOC ;; FIGURE ;; RAW_FILE ;; PATTERN

In the first form the line is split at its first three ` | `, so PATTERN may hold
`|` (a table row) but FIGURE may not; the second form, used whenever a line holds
` ;; `, lets FIGURE hold `|` too. DOC and RAW_FILE are relative to the repository.
FIGURE must occur in DOC exactly once (so a check cannot pass on a copy of the
figure elsewhere), and RAW_FILE must exist and contain PATTERN; both are plain
substrings, surrounding spaces stripped (tabs kept), neither empty. Lines starting
with # and empty lines are skipped. Prints each check as ok or FAIL; exits 1 if any
fails.

    python3 bench/check-figures.py [LIST]
"""
import sys
from pathlib import Path

root = Path(__file__).resolve().parent.parent
listing = Path(sys.argv[1]) if len(sys.argv) > 1 else root / "bench" / "figures.txt"
failed = 0
for number, line in enumerate(listing.read_text().splitlines(), 1):
    if not line.strip() or line.lstrip().startswith("#"):
        continue
    if " ;; " in line:
        parts = [p.strip(" ") for p in line.split(" ;; ")]
    else:
        parts = [p.strip(" ") for p in line.split(" | ", 3)]
    if len(parts) != 4 or not all(parts):
        print(f"FAIL line {number}: expected DOC | FIGURE | RAW_FILE | PATTERN, none empty")
        failed += 1
        continue
    doc, figure, raw, pattern = parts
    problems = []
    if not (root / doc).is_file():
        problems.append(f"{doc} missing")
    elif (count := (root / doc).read_text().count(figure)) != 1:
        problems.append(f"{figure!r} in {doc} {count} times, not once")
    raw_path = root / raw
    if not raw_path.is_file():
        problems.append(f"{raw} missing")
    elif pattern not in raw_path.read_text(errors="replace"):
        problems.append(f"{pattern!r} not in {raw}")
    print(("FAIL " if problems else "ok   ") + f"{doc}: {figure} <- {raw}" + (": " + "; ".join(problems) if problems else ""))
    failed += bool(problems)
print(f"{failed} of the checks failed" if failed else "every figure found in its raw file")
sys.exit(1 if failed else 0)
