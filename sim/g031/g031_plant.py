# SPDX-License-Identifier: Apache-2.0
"""The servo around a virtual G031: the plant of sim/plant (the integer C
model host-sim and the QEMU image run) driven by TIM3's two PWM outputs,
seen through the board's analog circuit on ADC_IN0..3.

The plant is built once per source version with the host's cc into a
shared library (g031_plant_shim.c + sim/plant/*.c, in the temporary
directory) and called through ctypes; docs/virtual-g031.md "The plant".

The circuit is the board's as boards/stm32g031/board_config.c describes
it (board_pins.h for the channels): a 270 deg pot whose wiper spans ADC
codes 205..3890 over -135..+135 deg, a 50 mOhm shunt into a gain-20
amplifier, a 100k/10k supply divider (1/11), a 10 kOhm B3950 NTC under a
10 kOhm pull-up, VREF 3.3 V, 12-bit codes. That calibration puts the
ADC's rails at +-150.0 deg, so the servo's hard stops sit inside them, at
ENDSTOP_DDEG, within what boards/stm32g031/product.c says its mechanics
can give (pos_read_min/max +-148.0 deg): docs/virtual-g031.md "The plant"."""
import ctypes
import hashlib
import math
import os
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
PLANT_DIR = os.path.join(os.path.dirname(HERE), "plant")
VREF_MV, FULL = 3300, 4095
POT_MIN, POT_MAX = 205, 3890
SHUNT_MOHM, SHUNT_GAIN, VDIV = 50, 20, 11
NTC_R25, NTC_B, NTC_PULLUP = 10000.0, 3950.0, 10000.0
ENDSTOP_DDEG = 1450   # the hard stops, 0.1 deg (sim/plant's own are at +-150.0, on this pot's rails)
DRIVE, COAST, BRAKE = 0, 1, 2
_LIB = []


def _sources():
    return [os.path.join(HERE, "g031_plant_shim.c")] + sorted(
        os.path.join(PLANT_DIR, n) for n in os.listdir(PLANT_DIR) if n.endswith((".c", ".h")))


def _read(path):
    """A file's bytes (closed at once)."""
    with open(path, "rb") as f:
        return f.read()


def library():
    """The plant library, built on first use (cc); cached by source hash."""
    if _LIB:
        return _LIB[0]
    srcs = _sources()
    digest = hashlib.sha256(b"".join(_read(p) for p in srcs)).hexdigest()[:16]
    path = os.path.join(tempfile.gettempdir(), "vg031-plant-%s-%d.so" % (digest, os.getuid()))
    if not os.path.exists(path):
        tmp = "%s.%d" % (path, os.getpid())
        subprocess.run(["cc", "-std=c11", "-O2", "-shared", "-fPIC", "-I", PLANT_DIR, "-o", tmp]
                       + [p for p in srcs if p.endswith(".c")], check=True)
        os.replace(tmp, path)
    lib = ctypes.CDLL(path)
    lib.g031_plant_size.restype = ctypes.c_size_t
    lib.g031_plant_init.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int32]
    lib.g031_plant_step.argtypes = [ctypes.c_void_p, ctypes.c_int32, ctypes.c_int32, ctypes.c_int32,
                                    ctypes.c_uint32]
    lib.g031_plant_read.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int32)]
    lib.g031_plant_event.argtypes = [ctypes.c_void_p, ctypes.c_int32, ctypes.c_int32]
    lib.g031_plant_time_ms.argtypes = [ctypes.c_void_p]
    lib.g031_plant_time_ms.restype = ctypes.c_uint32
    _LIB.append(lib)
    return lib


def ntc_code(temp_dc):
    """ADC code of the NTC divider at a winding temperature in 0.1 degC."""
    t = temp_dc / 10.0 + 273.15
    r = NTC_R25 * math.exp(NTC_B * (1.0 / t - 1.0 / 298.15))
    return int(round(FULL * r / (r + NTC_PULLUP)))


def _code(mv):
    """12-bit code of a voltage at the ADC pin (VREF full scale)."""
    return max(0, min(FULL, int(round(mv * FULL / VREF_MV))))


class Plant:
    """One servo's plant, stepped to the times the ADC samples it."""

    def __init__(self, config="realistic", scenario=()):
        self.lib = library()
        self.buf = ctypes.create_string_buffer(self.lib.g031_plant_size())
        if self.lib.g031_plant_init(self.buf, config.encode(), ENDSTOP_DDEG) != 0:
            raise ValueError("no plant configuration %r" % config)
        self.t_ns = None
        self.bridge, self.pwm = COAST, 0
        self.readings = (ctypes.c_int32 * 4)()
        self.scenario = list(scenario)   # [(t_ms, key, value)] on the plant's clock
        self.load_unm = 0
        self.lib.g031_plant_read(self.buf, self.readings)

    def drive_from(self, tim3, outputs_on):
        """The bridge input from TIM3 CH1 (IN1) and CH2 (IN2) in PWM mode 1:
        both low coast, both high brake, else drive by their difference."""
        d1 = tim3.duty(1) if outputs_on else 0.0
        d2 = tim3.duty(2) if outputs_on else 0.0
        if d1 >= 1.0 and d2 >= 1.0:
            self.bridge, self.pwm = BRAKE, 0
        elif d1 == 0.0 and d2 == 0.0:
            self.bridge, self.pwm = COAST, 0
        else:
            self.bridge, self.pwm = DRIVE, int(round((d1 - d2) * 1000))

    def advance(self, now_ns):
        """Steps the plant to virtual time now_ns with the bridge held."""
        if self.t_ns is None:
            self.t_ns = now_ns
        dt_us = int((now_ns - self.t_ns) // 1000)
        if dt_us <= 0:
            return
        self._play(self.lib.g031_plant_time_ms(self.buf))
        self.lib.g031_plant_step(self.buf, self.bridge, self.pwm, self.load_unm, dt_us)
        self.t_ns += dt_us * 1000
        self.lib.g031_plant_read(self.buf, self.readings)

    def _play(self, t_ms):
        """Applies the scenario events due at plant time t_ms (key 3, the
        load on the horn in mN*m, is held as the torque input)."""
        while self.scenario and self.scenario[0][0] <= t_ms:
            _t, key, value = self.scenario.pop(0)
            if key == 3:
                self.load_unm = value * 1000
            else:
                self.lib.g031_plant_event(self.buf, key, value)

    def code(self, channel):
        """The ADC code on ADC_IN<channel> now (board_pins.h channels 0..3)."""
        pos, ma, mv, temp = self.readings
        if channel == 0:
            return max(0, min(FULL, POT_MIN + (pos + 1350) * (POT_MAX - POT_MIN) // 2700))
        if channel == 1:
            return _code(abs(ma) * SHUNT_MOHM * SHUNT_GAIN // 1000)
        if channel == 2:
            return _code(mv / VDIV)
        if channel == 3:
            return ntc_code(temp)
        return 0
