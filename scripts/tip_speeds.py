#!/usr/bin/env python3
"""Tip-speed and J statistics of one run's crack_tips.csv (standard library only).

    python3 scripts/tip_speeds.py RUN_DIR/crack_tips.csv [--crack 0] [--tip 1] [--j-ic 250]

The speed measures are those of `fracture study rosakis` (lab/src/study/measure.rs,
`Measured`), so a run made with `fracture run` can be set beside the study's tables:
initiation (the first sample whose step advanced the tip, `growing`), "early" (mean speed over
the 10 us after initiation), "to end" (mean speed from initiation to the last sample), "late"
(largest 4 us moving-box speed later than 10 us after initiation), the mean speed in 10 us
windows after impact, and the tip's advance. Speeds come from the tip's x, its position along
the bond (the crack length along the polyline moves with the deforming faces; it is printed
as "length growth" only).

It adds what the study does not print: per time window the mean and the sample-to-sample
standard deviation of J (j1, J/m^2), the share of samples with J above the toughness, and the
share of samples that grew.
"""
import argparse
import csv
import statistics
import sys

WINDOWS_US = [(10, 20), (20, 30), (30, 40), (40, 50), (50, 60), (60, 70), (70, 80)]
J_WINDOWS_US = [(10, 40), (40, 80)]
BOX = 4e-6


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--crack", default="0")
    ap.add_argument("--tip", default="1", help="1: the notch tip of the Rosakis scenes")
    ap.add_argument("--j-ic", type=float, default=None, help="toughness (J/m^2) for the J shares")
    a = ap.parse_args()

    rows = [r for r in csv.DictReader(open(a.csv)) if r["crack"] == a.crack and r["tip"] == a.tip]
    if not rows:
        sys.exit(f"{a.csv}: no rows for crack {a.crack} tip {a.tip}")
    t = [float(r["time"]) for r in rows]
    length = [float(r["length"]) for r in rows]
    xs = [float(r["x"]) for r in rows]
    growing = [r["growing"] in ("1", "true", "True") for r in rows]

    def length_at(x):
        """The tip's x at time x (linear interpolation, clamped)."""
        for i, ti in enumerate(t):
            if ti >= x:
                if i == 0:
                    return xs[0]
                f = (x - t[i - 1]) / (t[i] - t[i - 1]) if t[i] > t[i - 1] else 1.0
                return xs[i - 1] + f * (xs[i] - xs[i - 1])
        return xs[-1]

    def mean_speed(lo, hi):
        if hi <= t[-1] + 1e-12 and hi > lo:
            return (length_at(hi) - length_at(lo)) / (hi - lo)
        return None

    def fmt(v):
        return "-" if v is None else f"{v:.1f}"

    print(f"{a.csv}: {len(rows)} samples to {t[-1] * 1e6:.2f} us")
    t0 = next((ti for ti, g in zip(t, growing) if g), None)
    if t0 is None:
        print("no growth")
    else:
        box = [
            (ti, (length_at(ti + BOX / 2) - length_at(ti - BOX / 2)) / BOX)
            for ti in t
            if ti - BOX / 2 >= 0 and ti + BOX / 2 <= t[-1]
        ]
        later = [v for ti, v in box if ti > t0 + 1e-5]
        late = max(later) if later and t[-1] > t0 + 1e-5 else None
        print(
            f"initiation {t0 * 1e6:.2f} us, early {fmt(mean_speed(t0, t0 + 1e-5))} m/s, "
            f"to end {fmt(mean_speed(t0, t[-1]))} m/s, late {fmt(late)} m/s, "
            f"tip advance {(xs[-1] - xs[0]) * 1e3:.3f} mm, tip x at the end "
            f"{xs[-1] * 1e3:.2f} mm, length growth (polyline) {(length[-1] - length[0]) * 1e3:.3f} mm"
        )
        print(
            "mean speed (m/s) in "
            + ", ".join(f"{lo}-{hi} us {fmt(mean_speed(lo * 1e-6, hi * 1e-6))}" for lo, hi in WINDOWS_US)
        )
    for lo, hi in J_WINDOWS_US:
        sel = [r for r in rows if lo * 1e-6 <= float(r["time"]) < hi * 1e-6]
        if not sel:
            continue
        j = [float(r["j1"]) for r in sel]
        line = f"J {lo}-{hi} us: mean {statistics.mean(j):.0f}, sd {statistics.pstdev(j):.0f} J/m^2"
        if a.j_ic is not None:
            line += f", above J_Ic in {100 * sum(x > a.j_ic for x in j) / len(j):.0f} %"
        grew = sum(r["growing"] in ("1", "true", "True") for r in sel)
        line += f", growing in {100 * grew / len(sel):.0f} % of samples"
        print(line)


if __name__ == "__main__":
    main()
