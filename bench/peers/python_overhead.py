#!/usr/bin/env python3
"""The Python package's cost per simulate call beyond the C++ run, on the sled (docs/python.md).

    PYTHONPATH=build/python /usr/bin/python3 bench/peers/python_overhead.py [--calls 2000]

For each call, the overhead is the wall time of Model.simulate minus the time the C++ side spent
in the same call (Result.cpp_seconds: option parsing, the run, the arrays). Prints the median and
the 90th percentile over the calls, for a short run (11 rows) and a longer one (1001 rows)."""

import argparse
import statistics
import time

import nhdyn


def measure(m, calls, **options):
    overheads, runs = [], []
    for _ in range(calls):
        start = time.perf_counter()
        r = m.simulate(**options)
        wall = time.perf_counter() - start
        overheads.append(wall - r.cpp_seconds)
        runs.append(r.cpp_seconds)
    overheads.sort()
    return statistics.median(runs), statistics.median(overheads), overheads[int(0.9 * len(overheads))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    args = parser.parse_args()
    m = nhdyn.load("sled")
    print("sled, {} calls each; times in microseconds".format(args.calls))
    print("{:>28} {:>12} {:>16} {:>16}".format("run", "C++ run", "overhead median", "overhead p90"))
    for label, options in (("t_end 0.1, 11 rows", dict(t_end=0.1, output_step=0.01)),
                           ("t_end 10, 1001 rows", dict(t_end=10.0, output_step=0.01))):
        measure(m, 50, **options)  # warm up
        run, median, p90 = measure(m, args.calls, **options)
        print("{:>28} {:>12.1f} {:>16.1f} {:>16.1f}".format(label, run * 1e6, median * 1e6, p90 * 1e6))


if __name__ == "__main__":
    main()
