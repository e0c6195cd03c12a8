"""Writes what NVIDIA's flip-evaluator package answers for a set of images that
fsot's FLIP test makes again bit for bit (integer hashes over 255), so the test
checks fsot's FLIP against the package without Python:

    "$(bench/flip/setup.sh)" bench/flip/reference.py > crates/fsot-cli/tests/data/flip-package.json

Each case: its size, pixels per degree, how its two images are made, the
package's mean error and its error map (row-major). Inputs are sRGB in [0, 1]
(`inputsRGB=True`, LDR), as `fsot eval` shows its frames.
"""
import json
import sys
from importlib.metadata import version

import numpy as np
import flip_evaluator as flip

M = 0xFFFFFFFF


def hash_byte(x, y, c, seed):
    """A byte from four integers (the test computes the same)."""
    h = ((x * 73856093) ^ (y * 19349663) ^ (c * 83492791) ^ (seed * 2654435761)) & M
    h ^= h >> 13
    h = (h * 0x5BD1E995) & M
    h ^= h >> 15
    return h >> 24


def image(kind, w, h, seed):
    """Bytes (h, w, 3) of one image; `kind` as the test names it."""
    out = np.zeros((h, w, 3), dtype=np.int64)
    for y in range(h):
        for x in range(w):
            for c in range(3):
                if kind == "grey-noise":
                    v = hash_byte(x, y, 0, seed)
                elif kind == "colour-noise":
                    v = hash_byte(x, y, c, seed)
                elif kind == "gradient":
                    # A ramp, plus noise of +-10 when seed is not 0.
                    v = (255 * (x + 2 * y)) // (w - 1 + 2 * (h - 1))
                    if seed:
                        v = min(255, max(0, v + hash_byte(x, y, 0, seed) % 21 - 10))
                elif kind == "step":
                    # Dark left, light right; the edge at w / 2 + seed.
                    v = 51 if x < w // 2 + seed else 204
                else:
                    raise SystemExit(f"unknown kind {kind}")
                out[y, x, c] = v
    return out


CASES = [
    # (name, width, height, ppd, reference (kind, seed), test (kind, seed))
    ("grey noise, fhd", 32, 24, 37.8, ("grey-noise", 1), ("grey-noise", 2)),
    ("grey noise, 4k", 32, 24, 75.4, ("grey-noise", 1), ("grey-noise", 2)),
    ("noisy gradient, 4k", 40, 28, 75.4, ("gradient", 0), ("gradient", 3)),
    ("moved step, fhd", 36, 20, 37.8, ("step", 0), ("step", 1)),
    ("colour noise, package default ppd", 24, 24, 67.0206, ("colour-noise", 4), ("colour-noise", 5)),
    ("grey noise, small eye", 20, 30, 12.5, ("grey-noise", 6), ("grey-noise", 7)),
    ("grey noise narrower than the filters, 4k", 10, 7, 75.4, ("grey-noise", 9), ("grey-noise", 10)),
    ("equal images", 16, 16, 60.0, ("grey-noise", 8), ("grey-noise", 8)),
]


def main():
    cases = []
    for name, w, h, ppd, ref, test in CASES:
        r = (image(ref[0], w, h, ref[1]) / 255.0).astype(np.float32)
        t = (image(test[0], w, h, test[1]) / 255.0).astype(np.float32)
        error_map, mean, _ = flip.evaluate(r, t, "LDR", inputsRGB=True, applyMagma=False,
                                           parameters={"ppd": ppd})
        cases.append({
            "name": name, "width": w, "height": h, "ppd": ppd,
            "reference": {"kind": ref[0], "seed": ref[1]},
            "test": {"kind": test[0], "seed": test[1]},
            "mean": float(mean),
            "map": [float(v) for v in np.asarray(error_map, dtype=np.float32).reshape(-1)],
        })
    json.dump({"package": "flip-evaluator " + version("flip-evaluator"), "cases": cases},
              sys.stdout, indent=None, separators=(",", ":"))
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
