"""The notebook-style example of python/README.md, runnable: load a record, decompose it, group the
IMFs by sample entropy, Allan deviation with its noise terms (plotted when matplotlib is installed),
with the PyEMD / AllanTools calls it replaces run side by side and timed when those packages can be
imported (they are optional: the script says when they are not).

    PYTHONPATH=build/python python3 python/examples/notebook.py [RECORD.csv] [--fs-hz 10] [--plot allan.png]
                                                              [--compare] [--repeat 3]

Without RECORD, the record is the simulated fmvmg oven run (driftlab.simulate, seed 1) at --fs-hz.
"""
import argparse
import time

import numpy as np

import driftlab


REPEAT = 1  # calls per timing (--repeat); the fastest counts


def timed(function, *args, **kwargs):
    """(result, seconds): the fastest of REPEAT calls, wall clock."""
    best = float("inf")
    for _ in range(REPEAT):
        start = time.perf_counter()
        result = function(*args, **kwargs)
        best = min(best, time.perf_counter() - start)
    return result, best


GROUPING = """format: driftlab-pipeline/1
inputs: {rate: rate}
steps:
  - {name: decompose, plugin: decomposition/emd, inputs: {signal: rate}}
  - name: classify
    plugin: classifier/sample_entropy
    inputs: {imfs: decompose.imfs, residue: decompose.residue}
    params: {m: 2, r: 0.2}
outputs: {noise: classify.noise, mixed: classify.mixed, drift: classify.drift}
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("record", nargs="?", help="a CSV or log with a rate and a temperature (default: simulated)")
    parser.add_argument("--fs-hz", type=float, default=10.0, help="sample rate of the simulated record, Hz")
    parser.add_argument("--duration-s", type=float, default=None, help="duration of the simulated record, s")
    parser.add_argument("--plot", help="write the Allan plot to this file (needs matplotlib)")
    parser.add_argument("--compare", action="store_true", help="also run and time PyEMD and AllanTools")
    parser.add_argument("--repeat", type=int, default=1, help="calls per timing, the fastest counts")
    args = parser.parse_args()
    global REPEAT
    REPEAT = args.repeat

    # 1. Load a record (SI units: rad/s, degC, s).
    if args.record:
        record = driftlab.read_record(args.record)
        rate, fs = record.channels["rate"], record.sample_rate_hz
    else:
        sim = driftlab.simulate("fmvmg", fs_hz=args.fs_hz, seed=1, duration_s=args.duration_s)
        rate, fs = sim["rate_rad_s"], args.fs_hz
    print(f"record: {len(rate)} samples at {fs:g} Hz")

    # 2. Decompose (EMD; eemd / ceemdan / vmd take the same call with their parameters).
    d, emd_s = timed(driftlab.emd, rate)
    assert np.allclose(d.imfs.sum(axis=0) + d.residue, rate, rtol=0, atol=1e-12 * np.abs(rate).max())
    print(f"driftlab.emd: {d.imfs.shape[0]} IMFs in {emd_s:.3f} s")

    # 3. Group by sample entropy: each IMF's SampEn(2, 0.2), and the groups classifier/sample_entropy
    #    forms from them (noise, mixed, drift), as li2023.yaml does.
    results, sampen_s = timed(lambda: [driftlab.sample_entropy(imf, m=2, r=0.2) for imf in d.imfs])
    entropies = [s.value for s in results]
    print("SampEn per IMF: " + ", ".join(f"{s:.3f}" for s in entropies) + f" ({sampen_s:.3f} s)")
    groups = driftlab.Pipeline.from_yaml(GROUPING).run({"rate": rate}, fs_hz=fs)
    for name in ("noise", "mixed", "drift"):
        print(f"  {name:5s} group: rms {np.sqrt(np.mean(groups.outputs[name] ** 2)) * driftlab.DEG_H_PER_RAD_S:.4g} deg/h")

    # 4. Allan deviation with intervals and the IEEE 952 readings.
    a, allan_s = timed(driftlab.allan, rate, fs_hz=fs, kind="oadev", taus="octave")
    n = a.arw_rad_sqrt_s * driftlab.DEG_H_PER_RAD_S
    b = a.bias_instability
    b_text = (f"{b.value_rad_s * driftlab.DEG_H_PER_RAD_S:.3g} deg/h" if b.resolved
              else f"< {b.high_rad_s * driftlab.DEG_H_PER_RAD_S:.3g} deg/h (no floor within tau <= {b.longest_tau_s:g} s)")
    print(f"driftlab.allan: {len(a.taus_s)} taus in {allan_s:.4f} s; N = {n:.4g} deg/h/sqrt(Hz), B {b_text}")

    if args.plot:
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no plot")
        else:
            scale = driftlab.DEG_H_PER_RAD_S
            fig, ax = plt.subplots()
            ax.loglog(a.taus_s, a.dev_rad_s * scale, "o-", label="OADEV")
            ax.fill_between(a.taus_s, a.dev_lo_rad_s * scale, a.dev_hi_rad_s * scale, alpha=0.3, label="68 % interval")
            ax.set_xlabel("tau (s)")
            ax.set_ylabel("Allan deviation (deg/h)")
            ax.legend()
            fig.savefig(args.plot)
            print(f"wrote {args.plot}")

    # 5. The calls driftlab replaces, on the same record, when installed.
    if args.compare:
        try:
            from PyEMD import EMD  # PyEMD (pip: EMD-signal)
        except ImportError as e:
            print(f"PyEMD not importable ({e}): not compared")
        else:
            imfs, pyemd_s = timed(EMD().emd, rate)
            print(f"PyEMD EMD().emd: {imfs.shape[0]} rows (IMFs + residue) in {pyemd_s:.3f} s "
                  f"({pyemd_s / emd_s:.0f} x driftlab.emd)")
        try:
            import allantools
        except ImportError as e:
            print(f"AllanTools not importable ({e}): not compared")
        else:
            (taus, devs, errors, ns), at_s = timed(allantools.oadev, rate, rate=fs, data_type="freq", taus="octave")
            print(f"allantools.oadev: {len(taus)} taus in {at_s:.4f} s ({at_s / allan_s:.1f} x driftlab.allan, "
                  f"which also gives intervals, edf and the noise terms)")


if __name__ == "__main__":
    main()
