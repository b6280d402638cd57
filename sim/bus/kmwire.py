# SPDX-License-Identifier: Apache-2.0
"""What a UART at one baud rate decodes from bytes sent at another: the
emulated bus's model of a baud mismatch (sim/bus/servo-bus, docs/
protocol-decisions.md "Baud on the emulated bus").

A sender puts each byte on the wire as 8N1 (start bit 0, 8 data bits LSB
first, stop bit 1) at its bit time, the bytes of one burst back to back,
the line idle (1) before and after. A receiver at its own bit time waits
for a falling edge, samples the start bit in its middle (still 0, else a
false start: it looks for the next edge), the 8 data bits and the stop bit
at their middles by its own clock, and then looks for the next edge from
the stop bit's middle on. A stop bit sampled 0 is a framing error: the
byte is dropped, as the servos' UART drivers and a USB adapter's driver
discard it (TCP cannot carry an error flag). Equal rates give the bytes
back unchanged; rates a few per cent apart still decode (the stop bit's
middle stays inside the sent stop bit), as on a real wire; a servo at
9600 on a 115200 bus sees no valid frame and stays silent.

Deterministic: the same burst at the same two rates always gives the same
bytes. Times are integers in units of 1 / (2 x tx x rx) s, so a bit is
2 x rx units at the sender and 2 x tx units at the receiver, exactly.
"""

BAUD_MIN = 9600      # the products' range (boards/sim-common/km_sim_product.c)
BAUD_MAX = 1000000


def baud_error(value):
    """None when value is a baud rate the servos can run at, else the reason
    (a one-line message for --baud)."""
    if isinstance(value, str):
        if not value.strip().isdigit():
            return "'%s' is not a baud rate: a positive whole number, %d..%d" % (value, BAUD_MIN, BAUD_MAX)
        value = int(value)
    if not BAUD_MIN <= value <= BAUD_MAX:
        return "%d baud is outside the servos' range %d..%d" % (value, BAUD_MIN, BAUD_MAX)
    return None


def _bits(data):
    out = []
    for b in data:
        out.append(0)
        out.extend((b >> i) & 1 for i in range(8))
        out.append(1)
    return out


def garble(data, tx_baud, rx_baud):
    """The bytes a receiver at rx_baud decodes from `data` sent back to back
    at tx_baud (framing errors dropped)."""
    data = bytes(data)
    if tx_baud == rx_baud or not data:
        return data
    bits = _bits(data)
    t_tx = 2 * rx_baud  # one sent bit, in units
    t_rx = 2 * tx_baud  # one received bit

    def level(t):
        k = t // t_tx
        return bits[k] if 0 <= k < len(bits) else 1

    out = bytearray()
    t = 0
    end = len(bits) * t_tx
    while True:
        # the next falling edge at or after t: a sent 0 bit after a 1
        k = -(-t // t_tx)
        while k < len(bits) and not (bits[k] == 0 and (k == 0 or bits[k - 1] == 1)):
            k += 1
        if k >= len(bits):
            return bytes(out)
        edge = k * t_tx
        if level(edge + t_rx // 2) != 0:  # a glitch, not a start bit
            t = edge + t_rx // 2
            continue
        value = 0
        for i in range(8):
            value |= level(edge + t_rx // 2 + (i + 1) * t_rx) << i
        stop_at = edge + t_rx // 2 + 9 * t_rx
        if level(stop_at) == 1:
            out.append(value)
        t = stop_at
        if t >= end:
            return bytes(out)


def import_rfc2217():
    """pyserial's RFC 2217 module, from this interpreter or Debian's
    python3-serial (host/kmx/deps.py); SystemExit naming the package."""
    from kmx.deps import import_debian
    from kmx.errors import MissingPackage
    try:
        return import_debian("serial.rfc2217", "python3-serial", "an RFC 2217 client of the bus")
    except MissingPackage as e:
        raise SystemExit("servo-bus: %s" % e)
