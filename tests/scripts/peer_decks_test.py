#!/usr/bin/python3
"""The peer benchmark times one Hertz law on both sides: the pair_coeff line of LAMMPS' deck
(perf/peer/bench.lmp, model hertz_tsuji) must be the line the engine's benchmark turns into
its own law (perf/bench_dem_throughput.cpp, kHertzTsujiCoeff). A change to one alone would
compare two different laws without any error.

    peer_decks_test.py [--selftest]
"""
import os
import re
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def engine_line(cpp):
    m = re.search(r"kHertzTsujiCoeff\s*=\s*((?:\s*\"[^\"]*\")+)\s*;", cpp)
    if not m:
        sys.exit("perf/bench_dem_throughput.cpp: no kHertzTsujiCoeff")
    return "".join(re.findall(r"\"([^\"]*)\"", m.group(1)))


def lammps_line(deck):
    m = re.search(r'"\$\{model\} == hertz_tsuji"\s*&\s*"pair_style granular"\s*&\s*"pair_coeff ([^"]*)"',
                  deck)
    if not m:
        sys.exit("perf/peer/bench.lmp: no hertz_tsuji model with a granular pair_coeff")
    return m.group(1)


def same(cpp, deck):
    return engine_line(cpp).split() == lammps_line(deck).split()


def main():
    cpp = open(os.path.join(ROOT, "perf", "bench_dem_throughput.cpp")).read()
    deck = open(os.path.join(ROOT, "perf", "peer", "bench.lmp")).read()
    if "--selftest" in sys.argv:  # the check must see a changed coefficient
        altered = deck.replace("hertz/material 1.365e12", "hertz/material 1.366e12")
        if altered == deck or same(cpp, altered):
            sys.exit("selftest: a changed modulus in the deck went unnoticed")
    if not same(cpp, deck):
        sys.exit("the engine's hertz_tsuji law (%s) is not LAMMPS' (%s)" %
                 (engine_line(cpp), lammps_line(deck)))
    print("engine and LAMMPS time the same law:", lammps_line(deck))


if __name__ == "__main__":
    main()
