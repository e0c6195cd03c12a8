#!/usr/bin/env python3
"""Writes masks/manifest.json (to stdout) from the work folder of make-masks.sh.

Usage: masks-manifest.py WORK ENTRY...
  WORK   the folder holding NAME.log (each mask's `fsot optimize` output) and
         eval/results.json and eval/results.md (the `fsot eval` run)
  ENTRY  "name|ktx2 format|optimize flags", as listed in make-masks.sh
"""
import json
import os
import re
import sys


def viewing(flags):
    """The display and time model a mask was made for, from its optimize flags."""
    kernel = re.search(r"--kernel (\S+)", flags).group(1)
    alpha = re.search(r"--alpha (\S+)", flags)
    alpha = alpha.group(1) if alpha else "0.1"
    eye = "standard_fhd (37.84 pixels per degree)"
    if kernel == "perceptual-taa":
        return f"{eye}, 60 fps, TAA alpha {alpha}"
    if kernel == "taa":
        return f"{eye}, no TAA: the eye's integration over frames as a blend of weight {alpha} per frame"
    sys.exit(f"masks-manifest.py: no description of kernel {kernel}")

work, entries = sys.argv[1], sys.argv[2:]
records = json.load(open(os.path.join(work, "eval", "results.json")))
header = open(os.path.join(work, "eval", "results.md")).read().split("\n")
made_by = next((line for line in header if line.startswith("fsot ")), "")
eval_command = open(os.path.join(work, "eval", "command.txt")).read().strip()


def figures(method):
    """Per display, scene and TAA setting: pRelMSE as a ratio to white noise and JOD."""
    white = {(r["scene"], r["display"], r["taa"]): r["prelmse"] for r in records if r["method"] == "white"}
    out = {}
    for r in records:
        if r["method"] != method:
            continue
        key = (r["scene"], r["display"], r["taa"])
        cell = out.setdefault(r["display"], {}).setdefault(r["scene"], {})
        cell["taa" if r["taa"] else "no_taa"] = {
            "prelmse_x_white": round(r["prelmse"] / white[key], 4),
            "jod": round(r["jod"], 3),
            "jod_ci95": round(r["jod_ci95"], 3),
        }
    return out


masks = []
for entry in entries:
    name, fmt, flags = entry.split("|")
    log = open(os.path.join(work, name + ".log")).read()
    ratio = re.search(r"\(([0-9.]+) x white noise\)", log)
    wall = re.search(r": ([0-9.]+) s wall", log)
    size = re.search(r"--size (\d+)x(\d+)x(\d+)", flags)
    dims = int(re.search(r"--dims (\d+)", flags).group(1))
    w, h, t = (int(v) for v in size.groups())
    masks.append(
        {
            "name": name,
            "ktx2": f"{name}.ktx2",
            "ktx2_format": fmt,
            "png": f"{name}/frame0000.png ... frame{t - 1:04}.png",
            "png_layout": "8-bit, grey (d = 1) or RGB with blue 0 (d = 2); a value is (q + 0.5) / 256",
            "ktx2_layout": "2-D array texture, one layer per frame; a value is fract(q / 255) (255 reads 1.0, which wraps to 0.0)",
            "ktx2_bytes": os.path.getsize(os.path.join("masks", f"{name}.ktx2")),
            "width": w,
            "height": h,
            "frames": t,
            "dims": dims,
            "display": viewing(flags),
            "command": f"fsot optimize --backend cpu {flags} --out {name}.ktx2 --ktx2-format {fmt} --png {name} --png-bits 8",
            "objective_x_white_exact": float(ratio.group(1)) if ratio else None,
            "seconds_to_make": float(wall.group(1)) if wall else None,
            "eval": figures(name),
        }
    )

manifest = {
    "licence": "CC0-1.0: the masks are dedicated to the public domain; use them for anything, with no attribution required",
    "made_by": "scripts/make-masks.sh",
    "checksums": "SHA256SUMS (sha256sum -c SHA256SUMS in masks/)",
    "made_on": made_by,
    "eval_command": eval_command,
    "eval_note": "fsot eval --quick of the KTX2 files (their 8-bit levels): pRelMSE as a ratio to white noise (lower is better), ColorVideoVDP JOD (10: no visible difference), per display and scene, with TAA and without; objective_x_white_exact is fsot's objective of the exact values the files round",
    "masks": masks,
    "published": {m: figures(m) for m in ("published-stbn", "published-fast") if any(r["method"] == m for r in records)},
}
json.dump(manifest, sys.stdout, indent=1)
sys.stdout.write("\n")
