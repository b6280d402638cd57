#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes docs/figures.md from measurements, never by hand: the real-path
benchmark of the shipped stm32g031 image (bench_realpath.py: instructions
and estimated M0+ cycles per byte, per command, per list length, per
control tick), the images' static worst-case stack (tools/check/image-check)
and the application's measured stack high-water (sim/g031/g031_figures.py),
the store's wear on the STM32G031 (the host benchmark bench_store_wear) and
the image's flash and RAM per module from its linker map
(tools/check/footprint). Everything in it is deterministic for a given build
(virtual time on sim/g031; the map; the host simulator of the flash), so
CTest's `figures_doc_current` checks that the committed file is what this
prints.

    PYTHONPATH=sim/g031 /usr/bin/python3 tests/bench/m0/figures.py [--build DIR] [--host-build HDIR] [--write | --check]

DIR: the stm32g031 preset's build directory (default build/stm32g031);
HDIR: the host preset's (default build/host), which holds
build/host/tests/bench_store_wear: missing, this fails. --f6-build F6DIR (a 32 KiB
build, KM_G031_FLASH_KB=32, as CTest board_stm32g031_f6_fit makes in
build/host/f6-fit) adds the 32 KiB budget lines and that image's hot
paths. Without --write or --check
the document goes to stdout."""
import argparse
import difflib
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
import bench_realpath  # beside this script; it needs sim/g031 on PYTHONPATH
import g031_figures  # sim/g031
import g031_cycles  # sim/g031

DOC = os.path.join(ROOT, "docs", "figures.md")
STEP = 8  # list lengths: 1, 9, 17, ... and the longest
# The shipped stm32g031 images whose stack is bounded, with what each is.
STACK_IMAGES = [("km-servo-app-stm32g031", "application (behind the bootloader)"),
                ("km-servo-stm32g031", "image without bootloader"),
                ("km-boot-stm32g031", "bootloader")]
HIGH_WATER_TARGET = 80  # % of the reserve, issue 21 goal 6
WEAR_ROWS = "STM32G031 "  # bench_store_wear's rows for the board's store geometry


def footprint(map_path):
    """tools/check/footprint's table for one image, as its lines."""
    tool = os.path.join(ROOT, "tools", "check", "footprint")
    out = subprocess.run([sys.executable, tool, map_path], check=True, capture_output=True, text=True).stdout
    return [ln.rstrip() for ln in out.splitlines() if ln.strip()]


def static_stack(build, name):
    """tools/check/image-check's static worst case for one image, as the
    build runs it after every link: (worst case B, reserve B, main's path)."""
    tool = os.path.join(ROOT, "tools", "check", "image-check")
    elf = os.path.join(build, "boards", "stm32g031", name + ".elf")
    cfg = os.path.join(ROOT, "boards", "stm32g031", "image-check.json")
    out = subprocess.run([sys.executable, tool, elf, "--config", cfg, "--su-root", build, "--checks", "stack"],
                         check=True, capture_output=True, text=True).stdout
    m = re.search(r"worst case (\d+) B; reserved (\d+) B", out)
    path = re.search(r"^stack \S+: main \(from \S+\) \d+ B via (.*)$", out, re.M)
    if not m or not path:
        raise RuntimeError("image-check printed no stack bound for %s:\n%s" % (name, out))
    return int(m.group(1)), int(m.group(2)), path.group(1)


def stack_section(build):
    """Static worst case and reserve of each shipped image, and the
    application's measured high-water against goal 6's target."""
    out = ["## Stack (stm32g031 images)", "",
           "Static worst case: `tools/check/image-check --checks stack` (run after every link;"
           " method in [footprint.md](footprint.md) \"Static worst-case stack\"): main's deepest"
           " path plus the deepest handler of each interrupt priority with its exception frame."
           " Reserve: the usable stack above the guard band.", "",
           "| image | static worst case | reserve | margin |", "|---|---|---|---|"]
    paths = []
    for name, what in STACK_IMAGES:
        worst, reserve, path = static_stack(build, name)
        out.append("| %s (`%s`) | %s B | %s B | %s B |" % (what, name, f"{worst:,}", f"{reserve:,}",
                                                          f"{reserve - worst:,}"))
        paths.append("- `%s`: %s" % (name, path))
    used, reserve = g031_figures.stack_high_water(os.path.join(build, "boards", "stm32g031"))
    pct = 100.0 * used / reserve
    out += ["", "Main's deepest path per image:", ""] + paths + ["",
            "Measured high-water of the application (boot + application images on the virtual G031,"
            " stack painted at boot; after a ping, the idle-time format of a blank store, a persisted"
            " setting and a ping 2.5 ms after it; sim/g031/g031_figures.py `stack_high_water`,"
            " CTest g031_first_saved_setting_ping_on_time checks the same traffic's mark):"
            " **%s B of the %s B reserve, %.0f %%** (target ≤ %d %%: %s)."
            % (f"{used:,}", f"{reserve:,}", pct, HIGH_WATER_TARGET,
               "met" if pct <= HIGH_WATER_TARGET else "NOT met"), ""]
    return out


def wear_exe(host_build):
    """The host benchmark bench_store_wear's path; exits with an error when
    the host preset has not built it (the figures never go without it)."""
    exe = os.path.join(host_build, "tests", "bench_store_wear")
    if not os.path.isfile(exe):
        raise SystemExit("figures.py: %s missing: build the host preset first"
                         " (cmake --build --preset host --target bench_store_wear)" % exe)
    return exe


def wear_section(host_build):
    """The STM32G031 rows of the host benchmark bench_store_wear, with its header."""
    exe = wear_exe(host_build)
    lines = subprocess.run([exe], check=True, capture_output=True, text=True).stdout.splitlines()
    head = lines[:lines.index(next(ln for ln in lines if ln.startswith("geometry"))) + 1]
    rows = [ln.rstrip() for ln in lines if ln.startswith(WEAR_ROWS)]
    if not rows:
        raise RuntimeError("bench_store_wear printed no %r rows" % WEAR_ROWS)
    return (["## Store wear (STM32G031 geometry: 2 KiB pages, 8-byte programs, 3 pages)", "",
             "`build/host/tests/bench_store_wear` (tests/bench/bench_store_wear.c; the store's code on a simulator of the"
             " board's flash geometry; method in [store.md](store.md)), its STM32G031 rows:", "", "```"]
            + [ln.rstrip() for ln in head] + rows + ["```", ""])


def f6_app_link(f6_build):
    """Links the application's .elf in a 32 KiB build (CTest's f6 fit builds
    only the images held to the budget): None when it links, else the
    linker's overflow line."""
    p = subprocess.run(["cmake", "--build", f6_build, "--target", "km-servo-app-stm32g031"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode == 0:
        return None
    over = re.search(r"region `FLASH' overflowed by \d+ bytes", p.stdout)
    if not over:
        raise RuntimeError("the 32 KiB application failed to build:\n" + p.stdout[-4000:])
    return over.group(0)


def f6_budget_section(f6_build):
    """tools/check/image-check's budget lines (issue 21 goal 6) for the
    images of a 32 KiB build (KM_G031_FLASH_KB=32): bootloader, application
    with its header, image without bootloader, RAM; an application that
    does not link there is shown with the linker's overflow."""
    tool = os.path.join(ROOT, "tools", "check", "image-check")
    cfg = os.path.join(ROOT, "boards", "stm32g031", "image-check.json")
    app_overflow = f6_app_link(f6_build)
    out = ["## 32 KiB part (STM32G031F6) budget", "",
           "`tools/check/image-check --checks budget` on the images of the 32 KiB build"
           " (`-DKM_G031_FLASH_KB=32`, CTest board_stm32g031_f6_fit; what gives way in"
           " [footprint.md](footprint.md) \"STM32G031F6\"):", "", "```"]
    for name, _what in STACK_IMAGES:
        elf = os.path.join(f6_build, "boards", "stm32g031", name + ".elf")
        if name == "km-servo-app-stm32g031" and app_overflow:
            budget = json.load(open(cfg))["budget"]
            limit = budget["flash"] - budget["boot_max"] - budget["store"]
            out.append("%s: does not link in the 32 KiB build (application + header: %s B left by the"
                       " bootloader and the store): %s" % (name, f"{limit:,}", app_overflow))
            continue
        p = subprocess.run([sys.executable, tool, elf, "--config", cfg, "--checks", "budget"],
                           capture_output=True, text=True)
        lines = [ln for ln in (p.stdout + p.stderr).splitlines() if "budget" in ln]
        if not lines:
            raise RuntimeError("image-check printed no budget line for %s:\n%s%s" % (elf, p.stdout, p.stderr))
        out += ["%s: %s" % (name, ln) for ln in lines]
    used, reserve = g031_figures.stack_high_water(os.path.join(f6_build, "boards", "stm32g031"))
    pct = 100.0 * used / reserve
    return out + ["```", "", "Measured stack high-water of the 32 KiB application (the same traffic as"
                  " above, through its bootloader): **%s B of the %s B reserve, %.0f %%** (target ≤ %d %%: %s)."
                  % (f"{used:,}", f"{reserve:,}", pct, HIGH_WATER_TARGET,
                     "met" if pct <= HIGH_WATER_TARGET else "NOT met"), ""]


def hot_path_rows(elf):
    """The real-path benchmark's rows of one image as a markdown table."""
    rows, _figs = bench_realpath.measure(elf, step=STEP)
    out = ["| figure | instructions | est. M0+ cycles | target (instructions) |", "|---|---|---|---|"]
    for fig, ins, cyc, tgt in rows:
        out.append("| %s | %s | %s | %s |" % (fig, ins or "—", cyc or "—", tgt or "—"))
    return out + [""]


def f6_hot_paths_section(f6_build):
    """The same real-path figures on the 32 KiB build's image without
    bootloader: its compact forms cost instructions (issue 21 goals 3, 4)."""
    elf = os.path.join(f6_build, "boards", "stm32g031", "km-servo-stm32g031.elf")
    return ["## 32 KiB part (STM32G031F6) hot paths", "",
            "The same benchmark on the 32 KiB build's image (`km-servo-stm32g031.elf` of"
            " `-DKM_G031_FLASH_KB=32`): its compact forms trade instructions for bytes"
            " ([footprint.md](footprint.md) \"What gives way in the 32 KiB build (decided)\").", ""
            ] + hot_path_rows(elf)


def instruction_classes(elf):
    """The virtual G031's section (helper vg031's, sim/g031/g031_cycles.py):
    instructions per class with their M0+ cycles on a few measured paths."""
    return g031_cycles.markdown(bench_realpath, elf)


def render(build, host_build, f6_build=None):
    images = os.path.join(build, "boards", "stm32g031")
    elf = os.path.join(images, "km-servo-stm32g031.elf")
    out = ["# Figures", "",
           "<!-- Generated by tests/bench/m0/figures.py --write; CTest figures_doc_current"
           " fails when this file is not what it prints. Do not edit. -->", "",
           "Measured on the shipped stm32g031 image (`km-servo-stm32g031.elf`) running on the"
           " virtual STM32G031 of sim/g031, in virtual time; the method, what each segment"
           " counts and the cycle model are in [benchmarks.md](benchmarks.md). Instructions"
           " are exact counts of the ARMv6-M instructions executed; cycles are Cortex-M0+"
           " estimates at the board's 64 MHz with 2 flash wait states. List lengths: every"
           " %d-th and the longest." % STEP, "",
           "## Hot paths", ""] + hot_path_rows(elf)
    out += g031_figures.markdown(images)
    out += instruction_classes(elf)
    out += stack_section(build)
    out += wear_section(host_build)
    if f6_build:
        out += f6_budget_section(f6_build)
        out += f6_hot_paths_section(f6_build)
    out += ["## Flash and RAM (stm32g031 servo image, from its linker map)", "", "```"]
    out += footprint(os.path.join(images, "km-servo-stm32g031.map"))
    out += ["```", "", "Reproduce: `cmake --build --preset stm32g031 && cmake --build --preset host"
            " --target bench_store_wear && PYTHONPATH=sim/g031 /usr/bin/python3"
            " tests/bench/m0/figures.py --f6-build build/host/f6-fit --write` (after CTest"
            " board_stm32g031_f6_fit has made that 32 KiB build).", ""]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "stm32g031"))
    ap.add_argument("--host-build", default=os.path.join(ROOT, "build", "host"))
    ap.add_argument("--f6-build", help="a 32 KiB build (KM_G031_FLASH_KB=32): its budget lines too")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    a = ap.parse_args()
    wear_exe(a.host_build)  # before the long measurements
    if a.f6_build and not os.path.isdir(os.path.join(a.f6_build, "boards", "stm32g031")):
        raise SystemExit("figures.py: %s holds no stm32g031 images: build it (CTest board_stm32g031_f6_fit)"
                         % a.f6_build)
    text = render(a.build, a.host_build, a.f6_build)
    if a.write:
        with open(DOC, "w") as f:
            f.write(text)
        return 0
    if a.check:
        have = open(DOC).read() if os.path.exists(DOC) else ""
        if have != text:
            sys.stdout.writelines(difflib.unified_diff(have.splitlines(True), text.splitlines(True),
                                                       "docs/figures.md", "measured"))
            print("figures.py: docs/figures.md is stale: run tests/bench/m0/figures.py --write",
                  file=sys.stderr)
            return 1
        return 0
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
