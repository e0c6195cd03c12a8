"""The FLIP of the records two `fsot eval` runs share (same scene, method,
display, TAA setting and sigma), side by side, with their difference: for
checking one FLIP against another on the same renders.

    python3 bench/flip/compare.py A.json B.json
"""
import json
import sys


def records(path):
    with open(path) as f:
        return {(r["scene"], r["method"], r["display"], r["taa"], r["sigma"]): r
                for r in json.load(f) if r.get("flip") is not None}


def main():
    if len(sys.argv) != 3:
        raise SystemExit("usage: compare.py A.json B.json")
    a, b = records(sys.argv[1]), records(sys.argv[2])
    shared = sorted(set(a) & set(b))
    if not shared:
        raise SystemExit("compare.py: no record has FLIP in both files")
    print("| scene | method | display | A | B | B - A | (B - A) / A | JOD A | JOD B |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    worst = 0.0
    for key in shared:
        ra, rb = a[key], b[key]
        d = rb["flip"] - ra["flip"]
        worst = max(worst, abs(d) / ra["flip"])
        print(f"| {key[0]} | {key[1]} | {key[2]} | {ra['flip']:.9f} | {rb['flip']:.9f} | {d:.2e} "
              f"| {d / ra['flip']:.2e} | {ra['jod']:.4f} | {rb['jod']:.4f} |")
    print(f"\n{len(shared)} records; the largest relative difference {worst:.2e}")


if __name__ == "__main__":
    main()
