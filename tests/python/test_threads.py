"""The GIL is released while a kernel runs (a Python thread keeps running meanwhile), results do not
depend on concurrent callers, and repeated calls do not leak."""
import pathlib
import sys
import threading
import time

import driftlab
import numpy as np
import pytest

RNG = np.random.default_rng(1)
X = RNG.standard_normal(200_000)
# A model fixture of the C++ tests (a driftlab-calibration/1 RBF model): the costliest compensator.
MODEL = pathlib.Path(__file__).parent.parent / "data" / "calibration" / "v1_rbf_ranged.json"


def longest_stall(call):
    """The longest time, as a fraction of the call's duration, for which a pure-Python thread made no
    progress while `call` ran in this thread: about 1 when `call` holds the GIL (the thread waits for
    it the whole time), small when `call` releases it. Unlike the thread's throughput, the longest
    stall does not depend on how busy the machine is: load spreads a thread's waits for a core into
    many short ones (milliseconds), while a held GIL is one wait as long as the call."""
    stalls = []  # (start, end) of every pause of the thread longer than a millisecond
    stop = False

    def spin():
        last = time.perf_counter()
        while not stop:
            now = time.perf_counter()
            if now - last > 1e-3:
                stalls.append((last, now))
            last = now

    previous = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)  # a held GIL then leaks at most 0.1 ms to the thread at the call's ends
    spinner = threading.Thread(target=spin)
    spinner.start()
    try:
        time.sleep(0.05)
        t0 = time.perf_counter()
        call()
        t1 = time.perf_counter()
        time.sleep(0.01)  # the stall that spans the call's end is recorded once the thread runs again
    finally:
        stop = True
        spinner.join()
        sys.setswitchinterval(previous)
    longest = max((min(end, t1) - max(start, t0) for start, end in stalls), default=0.0)
    return max(longest, 0.0) / (t1 - t0)


def test_the_measurement_tells_a_held_gil_from_a_released_one():
    values = RNG.standard_normal(500_000).tolist()
    # list.sort holds the GIL throughout: about 1; a sleep releases it: about 0 (a few ms of 200)
    assert longest_stall(lambda: sorted(values)) > 0.9
    assert longest_stall(lambda: time.sleep(0.2)) < 0.3


@pytest.mark.parametrize("name, call", [
    ("emd", lambda: driftlab.emd(X)),
    ("ceemdan", lambda: driftlab.ceemdan(X[:20_000], ensemble_size=10)),
    ("vmd", lambda: driftlab.vmd(X[:100_000], modes=4)),
    ("sample_entropy", lambda: [driftlab.sample_entropy(X[:100_000]) for _ in range(4)]),
    ("allan", lambda: driftlab.allan(np.tile(X, 10), 100.0)),
    ("simulate", lambda: driftlab.simulate("fmvmg", fs_hz=100.0, duration_s=1800)),
    ("simulate a whole IMU", lambda: driftlab.simulate("imu3", fs_hz=100.0, duration_s=1800)),
])
def test_a_python_thread_keeps_running_while_a_kernel_runs(name, call):
    assert longest_stall(call) < 0.5, name


def test_a_python_thread_keeps_running_while_a_record_is_read_compensated_and_run(tmp_path):
    n = 400_000
    t = np.arange(n) / 100.0
    temperature = 20 + 20 * np.sin(t / 600)
    path = tmp_path / "r.csv"
    np.savetxt(path, np.column_stack([t, np.degrees(X[: n // 2].repeat(2)), temperature]), delimiter=",",
               header="t_s,rate_dps,temp_c", comments="")
    assert longest_stall(lambda: driftlab.read_record(path)) < 0.5
    model = driftlab.load_calibration(MODEL)
    assert longest_stall(lambda: model.compensate(t, X[: n // 2].repeat(2), temperature)) < 0.5
    pipeline = driftlab.Pipeline.from_yaml("polynomial_baseline")
    inputs = {"time": t, "rate": X[: n // 2].repeat(2), "temperature": temperature}
    assert longest_stall(lambda: pipeline.run(inputs)) < 0.5


def test_a_python_thread_keeps_running_while_an_imu_is_calibrated_and_a_discrepancy_sought():
    imu = driftlab.simulate("imu3", fs_hz=2.0, seed=3)
    record = {"time": imu["time_s"], "temperature": imu["temp_c"], "temperature1": imu["temp1_c"],
              **{f"{s}{i}_{a}": imu[f"{s}{i}_{a}_{u}"] for i in ("", "1") for s, u in (("gyro", "rad_s"), ("accel", "mps2"))
                 for a in "xyz"}}
    fitted = driftlab.calibrate(record, model="poly")
    assert longest_stall(lambda: driftlab.calibrate(record)) < 0.5
    # Compensation is fast: on the 2-Hz record the (GIL-held) conversion of the dict's arrays is as
    # long as the kernel (the stall would be about half the call); at 10 Hz the kernel dominates.
    imu10 = driftlab.simulate("imu3", fs_hz=10.0, seed=3)
    record10 = {"time": imu10["time_s"], "temperature": imu10["temp_c"], "temperature1": imu10["temp1_c"],
                **{f"{s}{i}_{a}": imu10[f"{s}{i}_{a}_{u}"] for i in ("", "1")
                   for s, u in (("gyro", "rad_s"), ("accel", "mps2")) for a in "xyz"}}
    assert longest_stall(lambda: fitted.model.compensate(record10)) < 0.5
    oven = driftlab.simulate("fmvmg", fs_hz=1.0, seed=4)
    single = {"time": oven["time_s"], "rate": oven["rate_rad_s"], "temperature": oven["temp_c"]}
    assert longest_stall(lambda: driftlab.discrepancy(single, device="fmvmg")) < 0.5


def test_kernels_called_from_several_threads_at_once_give_the_sequential_results():
    x = X[:50_000]
    calls = [lambda: driftlab.emd(x).imfs, lambda: driftlab.ceemdan(x[:5000], ensemble_size=4).imfs,
             lambda: driftlab.allan(x, 100.0).dev_rad_s, lambda: np.array([driftlab.sample_entropy(x).a])]
    sequential = [call() for call in calls]
    concurrent = [None] * (2 * len(calls))
    threads = [threading.Thread(target=lambda i=i: concurrent.__setitem__(i, calls[i % len(calls)]()))
               for i in range(len(concurrent))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i, result in enumerate(concurrent):
        assert np.array_equal(result, sequential[i % len(calls)])


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_a_thousand_calls_do_not_leak(tmp_path):
    x = X[:2048]
    path = tmp_path / "r.csv"
    path.write_text("t_s,rate_dps\n" + "".join(f"{i},{v!r}\n" for i, v in enumerate(X[:4000])))
    oven = driftlab.simulate("imu3", fs_hz=1.0, seed=3)
    gyro = {"time": oven["time_s"], "gyro_x": oven["gyro_x_rad_s"], "temperature": oven["temp_c"]}

    def calls():
        d = driftlab.emd(x)
        assert d.imfs.shape[1] == x.size
        driftlab.allan(x, 100.0)
        driftlab.sample_entropy(x)
        r = driftlab.read_record(path)
        assert r.channels["rate"].size == 4000
        imu = driftlab.simulate("imu3", fs_hz=10.0, duration_s=60)
        model = driftlab.calibrate(gyro, model="poly").model
        assert model.compensate({"time": imu["time_s"], "gyro_x": imu["gyro_x_rad_s"],
                                 "temperature": imu["temp_c"]})["gyro_x"].size == 600
        try:
            driftlab.emd(x, s_number=0)
        except driftlab.ConfigError:
            pass

    for _ in range(100):  # allocator pools and caches settle
        calls()
    before = resident_bytes()
    for _ in range(1000):
        calls()
    # A leaked result would be ~0.2 MB per iteration (IMFs 0.15 MB, the record 0.06 MB, the IMU
    # record 0.2 MB): 200 MB or more in all.
    assert resident_bytes() - before < 20e6
