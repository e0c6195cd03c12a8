#!/usr/bin/env python3
"""One method against others in `fsot eval` results.json: per display, TAA
setting and scene, the method's JOD, pRelMSE (the column's sigma, and the
display's eye where measured) and FLIP (after TAA, where
measured) beside each other method's, and the verdict: ahead or behind where
the 95% intervals do not overlap, else level. Where the records hold each
placement's values (both methods judged at the same placements), the verdict
placement by placement follows in brackets when it differs: ahead or behind
where the 95% interval of the differences clears zero; beside it, for JOD, the
mean difference, its interval and the two methods' correlation over placements
(r: how alike a placement moves both, which is what pairing gains from).

    python3 bench/eval/compare.py RESULTS.json METHOD OTHER...
"""
import json
import math
import sys

# Two-sided 95% quantiles of Student's t, 1 to 30 degrees of freedom.
T95 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145,
       2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048,
       2.045, 2.042]


def t95(dof):
    if dof <= 30:
        return T95[dof - 1]
    z, v = 1.959964, float(dof)
    return z + (z**3 + z) / (4 * v) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * v * v)


def verdict(a, a_ci, b, b_ci, higher_better):
    if a - a_ci > b + b_ci:
        return "ahead" if higher_better else "behind"
    if a + a_ci < b - b_ci:
        return "behind" if higher_better else "ahead"
    return "level"


def difference(m, r, key):
    """The mean of m's values minus r's, placement by placement, and the
    half-width of its 95% interval; None without paired placements."""
    a = m.get("placements", {}).get(key) or []
    b = r.get("placements", {}).get(key) or []
    if len(a) != len(b) or len(a) < 2 or any(x is None for x in a + b):
        return None
    d = [x - y for x, y in zip(a, b)]
    n = len(d)
    mean = sum(d) / n
    ci = t95(n - 1) * math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1) / n)
    if not math.isfinite(mean) or not math.isfinite(ci):
        return None
    return mean, ci, correlation(a, b)


def correlation(a, b):
    """Pearson's correlation of two methods' values over the placements (how
    alike a placement moves both; 0 where either does not move)."""
    ma, mb = sum(a) / len(a), sum(b) / len(b)
    sa = math.sqrt(sum((x - ma) ** 2 for x in a))
    sb = math.sqrt(sum((y - mb) ** 2 for y in b))
    if sa == 0 or sb == 0:
        return 0.0
    return sum((x - ma) * (y - mb) for x, y in zip(a, b)) / (sa * sb)


def paired(m, r, key, higher_better):
    """The verdict from the differences placement by placement, or None."""
    d = difference(m, r, key)
    return None if d is None else verdict(d[0], d[1], 0.0, 0.0, higher_better)


def jod(r):
    if r.get("jod") is None or r.get("jod_ci95") is None:
        return "n/a"
    return f"{r['jod']:.3f} +- {r['jod_ci95']:.3f}"


def main():
    path, method, others = sys.argv[1], sys.argv[2], sys.argv[3:]
    records = json.load(open(path))
    displays = list(dict.fromkeys(r["display"] for r in records))
    scenes = list(dict.fromkeys(r["scene"] for r in records))
    sigmas = list(dict.fromkeys(r["sigma"] for r in records))
    for display, sigma, taa in ((d, s, t) for d in displays for s in sigmas for t in (True, False)):
        at = {
            (r["scene"], r["method"]): r
            for r in records
            if r["display"] == display and r["sigma"] == sigma and r["taa"] == taa
        }
        if not any(k[1] == method for k in at):
            continue
        of_sigma = f", sigma {sigma}" if len(sigmas) > 1 else ""
        print(f"\n{method} on {display}{of_sigma}, {'with' if taa else 'without'} TAA\n")
        head = ["scene", f"{method} JOD"] + [f"{o} JOD" for o in others]
        judges = [("jod", "jod_ci95", True, "JOD"), ("prelmse", "prelmse_ci95", False, "pRelMSE")]
        if any(r.get("prelmse_display") is not None for r in at.values()):
            judges.append(("prelmse_display", "prelmse_display_ci95", False, "pRelMSE (display's eye)"))
        if taa and any(r.get("flip") is not None for r in at.values()):
            judges.append(("flip", "flip_ci95", False, "FLIP"))
        head += [f"vs {o}: {j[3]}" for o in others for j in judges]
        paired_jod = any(m.get("placements") for m in at.values())
        if paired_jod:
            head += [f"JOD minus {o}'s, placement by placement (r)" for o in others]
        print("| " + " | ".join(head) + " |")
        print("|" + " --- |" * len(head))
        counts, by_pair = {}, {}
        for s in scenes:
            m = at.get((s, method))
            if m is None:
                continue
            row = [s, jod(m)]
            row += [jod(at[(s, o)]) if (s, o) in at else "" for o in others]
            for o in others:
                r = at.get((s, o))
                for key, ci, hb, name in judges:
                    # A value the JSON could not hold (NaN, infinity: null) is no verdict.
                    if r is None or any(x.get(k) is None for x in (m, r) for k in (key, ci)):
                        row.append("")
                        continue
                    v = verdict(m[key], m[ci], r[key], r[ci], hb)
                    counts.setdefault((o, name), {}).setdefault(v, 0)
                    counts[(o, name)][v] += 1
                    p = paired(m, r, key, hb)
                    if p is not None:
                        by_pair.setdefault((o, name), {}).setdefault(p, 0)
                        by_pair[(o, name)][p] += 1
                    row.append(v if p is None or p == v else f"{v} (paired: {p})")
            if paired_jod:
                for o in others:
                    d = difference(m, at[(s, o)], "jod") if (s, o) in at else None
                    row.append("" if d is None else f"{d[0]:+.3f} +- {d[1]:.3f} (r {d[2]:+.2f})")
            print("| " + " | ".join(row) + " |")
        for (o, name), c in counts.items():
            line = f"- vs {o} by {name}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items()))
            if (o, name) in by_pair:
                line += "; placement by placement: " + ", ".join(
                    f"{k} {v}" for k, v in sorted(by_pair[(o, name)].items()))
            print(line)


if __name__ == "__main__":
    main()
