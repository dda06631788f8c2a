"""allan: closed forms for white rate noise, the command line (`driftlab allan`, same code:
bit-identical curves), unit conversion at the boundary and the errors."""
import json

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns, write_record

FS_HZ = 128.0  # a power of two: the CSV's time stamps and the derived sample rate are exact
SIGMA = 0.02   # rad/s per sample


def white_rate(n=200_000, seed=5):
    return SIGMA * np.random.default_rng(seed).standard_normal(n)


@pytest.mark.parametrize("kind", ["oadev", "adev", "hdev", "ohdev", "totdev"])
def test_white_rate_noise_follows_sigma_over_sqrt_tau_fs_within_its_interval(kind):
    # White rate (frequency) noise: sigma_y(tau) = sigma / sqrt(tau fs) for the Allan and Hadamard
    # kinds and TOTDEV alike (NIST SP 1065 Table 6). Checked against each point's own 99 % interval.
    x = white_rate(n=50_000 if kind == "totdev" else 200_000)
    a = driftlab.allan(x, FS_HZ, kind=kind, confidence=0.99)
    truth = SIGMA / np.sqrt(a.taus_s * FS_HZ)
    averages = a.samples / a.m
    # The lag-1 autocorrelation identification (>= 30 averages) recognises the white rate noise.
    assert np.all(a.alpha[averages >= 30] == 0)
    # The interval is that of the identified noise type. Where it is white rate noise the truth lies
    # inside; at the longest taus (a few averages) the B1-ratio identification can name another type
    # (alpha = 1 at 6 averages: edf ~100 instead of ~5), so the interval belongs to other noise.
    white = a.alpha == 0
    assert np.count_nonzero(white) >= 10
    assert np.all(a.dev_lo_rad_s[white] <= truth[white]) and np.all(truth[white] <= a.dev_hi_rad_s[white])


def test_white_rate_noise_gives_N_as_sigma_over_sqrt_fs():
    a = driftlab.allan(white_rate(), FS_HZ, confidence=0.99)
    expected = SIGMA / np.sqrt(FS_HZ)  # rad/sqrt(s): sigma(1 s) * sqrt(1 s)
    one = np.argmin(np.abs(a.taus_s - 1.0))
    assert a.taus_s[one] == 1.0
    assert a.dev_lo_rad_s[one] <= expected <= a.dev_hi_rad_s[one]
    assert a.arw_rad_sqrt_s == pytest.approx(a.dev_rad_s[one], rel=1e-12)  # the -1/2 line through tau = 1 s
    n = a.noise_terms.N_rad_sqrt_s
    assert n.resolved and abs(n.value - expected) <= 3 * n.sigma


@pytest.mark.parametrize("kind, taus", [("oadev", "octave"), ("mdev", "decade"), ("totdev", "dense:5"),
                                        ("adev", "0.5,1,2,7")])
def test_the_curve_and_readings_equal_driftlab_allan_on_the_same_data(cli, tmp_path, kind, taus):
    x = white_rate(n=20_000) + 1e-4 * np.cumsum(np.random.default_rng(2).standard_normal(20_000)) / FS_HZ
    args = write_record(tmp_path / "x.csv", x, FS_HZ)
    cli("allan", *args, "--kind", kind, "--taus", taus, "--out", "allan.csv", "--json", "summary.json")
    expected = read_csv_columns(tmp_path / "allan.csv")
    summary = json.loads((tmp_path / "summary.json").read_text())
    a = driftlab.allan(x, FS_HZ, kind=kind, taus=[float(t) for t in taus.split(",")] if "," in taus else taus)
    for ours, theirs in [(a.taus_s, "tau_s"), (a.dev_rad_s, "dev"), (a.dev_lo_rad_s, "dev_lo"),
                         (a.dev_hi_rad_s, "dev_hi"), (a.n, "n")]:
        assert np.array_equal(ours, expected[theirs]), theirs
    readings = summary["readings"]
    b = a.bias_instability
    assert readings["B_flat_floor"]["resolved"] == b.resolved
    if b.resolved:
        assert readings["B_flat_floor"]["value"] == b.value_rad_s * driftlab.DEG_H_PER_RAD_S
    else:
        assert readings["B_flat_floor"]["value"] is None
        assert readings["B_flat_floor"]["upper"] == b.high_rad_s * driftlab.DEG_H_PER_RAD_S
    assert readings["B_flat_floor"]["tau_s"] == b.tau_s
    assert readings["N_at_1s"]["value"] == a.arw_rad_sqrt_s * driftlab.DEG_H_PER_RAD_S
    terms = a.noise_terms
    for key, term in [("N", terms.N_rad_sqrt_s), ("B", terms.B_rad_s), ("K", terms.K_rad_s_sqrt_s)]:
        assert summary["si"][key]["resolved"] == term.resolved
        assert summary["si"][key]["fitted"] == term.fitted
        if term.resolved:
            assert summary["si"][key]["value"] == term.value
        else:
            assert summary["si"][key]["upper"] == term.high


def test_other_rate_units_are_converted_to_rad_s_at_the_boundary(cli, tmp_path):
    x_dps = np.degrees(white_rate(n=10_000))
    a = driftlab.allan(x_dps, FS_HZ, unit="deg/s")
    b = driftlab.allan(x_dps * (np.pi / 180), FS_HZ)
    assert np.array_equal(a.dev_rad_s, b.dev_rad_s)
    args = write_record(tmp_path / "x.csv", x_dps, FS_HZ, unit="deg/s")
    cli("allan", *args, "--out", "allan.csv", "--json", "summary.json")
    assert json.loads((tmp_path / "summary.json").read_text())["si"]["N"]["value"] == a.noise_terms.N_rad_sqrt_s.value


def test_an_integrated_angle_gives_the_deviations_of_its_rate():
    x = white_rate(n=10_000)
    angle = np.concatenate([[0.0], np.cumsum(x) / FS_HZ])  # rad
    from_angle = driftlab.allan(angle, FS_HZ, input="angle")
    from_rate = driftlab.allan(x, FS_HZ)
    assert np.array_equal(from_angle.taus_s, from_rate.taus_s)
    # The same differences of the same angle, up to the rate's mean that integration removes first.
    assert from_angle.dev_rad_s == pytest.approx(from_rate.dev_rad_s, rel=1e-9)


def test_lists_are_accepted_and_the_input_is_not_modified():
    x = white_rate(n=1000)
    kept = x.copy()
    assert np.array_equal(driftlab.allan(x.tolist(), FS_HZ).dev_rad_s, driftlab.allan(x, FS_HZ).dev_rad_s)
    assert np.array_equal(x, kept)


def test_a_record_too_short_for_the_readings_still_has_its_curve():
    a = driftlab.allan(white_rate(n=8), FS_HZ)  # an analysis needs 9 samples, a curve 2
    assert len(a.taus_s) >= 1
    assert a.bias_instability is None and a.arw_rad_sqrt_s is None and a.noise_terms is None
    assert a.note.startswith("no ")


def test_bad_arguments_are_ConfigErrors_and_bad_data_DataErrors():
    x = white_rate(n=1000)
    with pytest.raises(driftlab.ConfigError, match="kind"):
        driftlab.allan(x, FS_HZ, kind="xdev")
    with pytest.raises(driftlab.ConfigError, match="angular-rate unit"):
        driftlab.allan(x, FS_HZ, unit="m/s^2")
    with pytest.raises(driftlab.ConfigError):
        driftlab.allan(x, FS_HZ, taus="weekly")
    with pytest.raises(driftlab.ConfigError, match="strictly between 0 and 1"):
        driftlab.allan(x, FS_HZ, confidence=1.5)
    with pytest.raises(driftlab.ConfigError, match="fs_hz"):
        driftlab.allan(x, 0.0)
    with pytest.raises(driftlab.ConfigError):
        driftlab.allan(x, FS_HZ, taus=[1e6])
    with pytest.raises(driftlab.DataError):
        driftlab.allan([0.1], FS_HZ)
