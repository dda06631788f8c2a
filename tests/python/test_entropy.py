"""sample_entropy: counts against a hand count and an independent pairwise count of the definition,
the command line (`driftlab entropy`), and the classifier's declared defaults."""
import inspect
import math
import re

import driftlab
import numpy as np
import pytest
from conftest import write_record


def pairwise_counts(x, m, tolerance):
    """Richman & Moorman's definition with PhysioNet sampen.c's conventions, counted pair by pair:
    N - m templates for both lengths, Chebyshev distance < tolerance, pairs i < j."""
    n = len(x)
    b = a = 0
    for i in range(n - m):
        for j in range(i + 1, n - m):
            if all(abs(x[i + k] - x[j + k]) < tolerance for k in range(m)):
                b += 1
                if abs(x[i + m] - x[j + m]) < tolerance:
                    a += 1
    return a, b


def test_a_hand_counted_sequence():
    # x = 1 2 1 2 1 3; population SD 0.745, so r = 0.2 gives a tolerance of 0.149: only equal values
    # match. The N - m = 4 templates of length 2 are 12 21 12 21: pairs (0,2), (1,3) match, B = 2.
    # Those of length 3 are 121 212 121 213: only (0,2) matches, A = 1. SampEn = -ln(1/2) = ln 2.
    s = driftlab.sample_entropy([1, 2, 1, 2, 1, 3], m=2, r=0.2)
    assert (s.a, s.b, s.n, s.m, s.status) == (1, 2, 6, 2, "finite")
    assert s.value == pytest.approx(math.log(2), rel=1e-15)
    assert s.tolerance == pytest.approx(0.2 * np.std([1, 2, 1, 2, 1, 3]), rel=1e-15)


@pytest.mark.parametrize("m", [0, 1, 2, 3])
@pytest.mark.parametrize("r", [0.1, 0.2, 0.5])
def test_the_counts_equal_a_pairwise_count_of_the_definition(m, r):
    x = np.cumsum(np.random.default_rng(m).standard_normal(300)) * 0.1 + np.random.default_rng(9).standard_normal(300)
    s = driftlab.sample_entropy(x, m=m, r=r)
    assert (s.a, s.b) == pairwise_counts(x.tolist(), m, s.tolerance)
    assert s.tolerance == pytest.approx(r * np.std(x), rel=1e-14)  # population SD, divisor N (summed apart)


def test_the_results_equal_driftlab_entropy_on_the_same_data(cli, tmp_path):
    x = np.random.default_rng(4).standard_normal(5000) + np.sin(np.arange(5000) * 0.01)
    args = write_record(tmp_path / "x.csv", x, 128.0)
    for m, r in [(2, 0.2), (1, 0.15), (3, 0.3)]:
        out = cli("entropy", *args, "--m", m, "--r", r)
        s = driftlab.sample_entropy(x, m=m, r=r)
        assert int(re.search(r"^A = (\d+)", out, re.M).group(1)) == s.a
        assert int(re.search(r"^B = (\d+)", out, re.M).group(1)) == s.b
        assert float(re.search(r"\) = ([0-9.]+)", out).group(1)) == pytest.approx(s.value, abs=5e-7)  # printed %.6f


def test_the_defaults_are_the_sample_entropy_classifiers():
    table = {p["key"]: p["default"] for p in driftlab.plugin_info("classifier/sample_entropy")["params"]}
    signature = inspect.signature(driftlab.sample_entropy)
    assert signature.parameters["m"].default == table["m"] == 2
    assert signature.parameters["r"].default == table["r"] == 0.2


def test_no_matches_and_undefined_are_results_not_errors():
    assert driftlab.sample_entropy([0, 1, 2, 3, 4, 5, 6, 7]).status == "undefined"  # no two templates match
    s = driftlab.sample_entropy([0, 0, 1, 1, 0, 0, 1, 1, 5], m=1, r=0.01)
    assert s.status == "finite"
    s = driftlab.sample_entropy([0, 0, 9, 9, 1, 1, 8, 8], m=1, r=0.01)  # pairs 00 match, then 9 vs 1 do not
    assert (s.a, s.status, s.value) == (0, "no_matches", math.inf)


def test_out_of_range_parameters_are_ConfigErrors_with_the_tables_constraints():
    with pytest.raises(driftlab.ConfigError, match="m: .*must be \\[0, 10\\]") as info:
        driftlab.sample_entropy([1.0, 2.0, 3.0], m=11)
    assert info.value.problems[0]["field"] == "m"
    with pytest.raises(driftlab.ConfigError, match="r: .*must be > 0"):
        driftlab.sample_entropy([1.0, 2.0, 3.0], r=0.0)


def test_bad_data_is_a_DataError():
    with pytest.raises(driftlab.DataError, match="sample 1 is NaN"):
        driftlab.sample_entropy([1.0, math.nan, 2.0])
    with pytest.raises(driftlab.DataError):
        driftlab.sample_entropy([])
