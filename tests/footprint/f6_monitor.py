#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""kmx monitor against servos without the multi-ID read 0x82: two virtual
STM32G031s (servo-bus --backend g031) running the 32 KiB build's servo
image, which leaves 0x82 out (KM_G031_MULTI_READ=OFF, docs/footprint.md
"What gives way"), so each 0x82 is an unsupported command there (§4 bit 5,
no answer). kmx's monitor_sample (kmx monitor and the web live view) must
read such a servo by 0x02 after its first silent 0x82: the first sample's
status shows bit 5 (the 0x82 it really refused), later samples' do not,
and every value is read.

    f6_monitor.py BUILD_DIR   (the build of board_stm32g031_f6_fit, CTest
                               board_stm32g031_f6_kmx_monitor)
"""
import os
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
sys.path[:0] = [os.path.join(REPO, "host"), os.path.join(REPO, "sim", "g031")]
import g031_servo_bus  # noqa: E402  (sim/g031)
from kmx import cli  # noqa: E402
from kmx.bus import Bus  # noqa: E402
from kmx.registers import Registers  # noqa: E402

IDS = (1, 2)
SAMPLES = 4
BIT5 = 0x20  # §4: unsupported command


def check_samples(spec):
    """SAMPLES monitor samples of both servos; the failures."""
    fails = []
    with Bus(spec, timeout=0.5) as bus:
        regs = Registers(bus)
        for n in range(SAMPLES):
            sample = cli.monitor_sample(bus, regs, cli.MONITOR + ("status",), IDS)
            for i in IDS:
                *values, status = sample[i]
                code = status.raw[0]
                print("sample %d, ID %d: %s; status 0x%02X (%s)" % (
                    n, i, ", ".join(str(v) for v in values), code, ", ".join(cli.fr.status_words(code))), flush=True)
                if len(values) != len(cli.MONITOR) or any(v is None for v in values):
                    fails.append("sample %d, ID %d: values missing: %r" % (n, i, values))
                if n == 0 and not code & BIT5:
                    fails.append("sample 0, ID %d: no bit 5 after the 0x82 it refused (is 0x82 built?)" % i)
                if n > 0 and code & BIT5:
                    fails.append("sample %d, ID %d: status bit 5 again: an 0x82 still sent to it" % (n, i))
        by_0x02 = getattr(regs, "no_multi_read", set())  # Registers.read_each's record; none before it
        if by_0x02 != set(IDS):
            fails.append("servos read by 0x02 only: %r, expected %r" % (sorted(by_0x02), list(IDS)))
    return fails


def main():
    image = os.path.join(sys.argv[1], "boards", "stm32g031", "km-servo-stm32g031.elf")
    if not os.path.isfile(image):
        print("FAIL: missing %s (CTest board_stm32g031_f6_fit builds it)" % image)
        return 1
    tmp = tempfile.TemporaryDirectory(prefix="f6-monitor-")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path[:2] + [os.environ.get("PYTHONPATH", "")]))
    try:
        with g031_servo_bus.servo_bus(IDS, ["--image", image, "--timeout", "60"], tmp.name, env) as (spec, _clock):
            fails = check_samples(spec)
    finally:
        tmp.cleanup()
    for f in fails:
        print("FAIL:", f)
    if fails:
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
