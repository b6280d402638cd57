# SPDX-License-Identifier: Apache-2.0
"""The single-wire bus between virtual G031 servos and a master, in virtual
time: what a UART at one bit time decodes from a byte sent at another.

A byte is 8N1 (start 0, 8 data bits LSB first, stop 1), the line idle (1)
around it. The receiver (RM0444 §33.5.6, 16x oversampling) detects the
falling edge, checks the start bit in its middle, samples the data bits
and the stop bit at their middles by its own clock; a stop bit sampled 0
is a framing error (FE, §33.5.6), the byte is lost to the protocol. Rates
within the receiver's tolerance (§33.5.8: about 3.75 % for 16x
oversampling without noise) decode unchanged."""

TOLERANCE = 0.0375


def decode(byte, tx_bit_ns, rx_bit_ns):
    """(value, framing_error) a receiver with bit time rx_bit_ns reads from
    `byte` sent alone at tx_bit_ns; None when it sees no start bit."""
    if abs(tx_bit_ns - rx_bit_ns) <= TOLERANCE * rx_bit_ns:
        return byte, False
    bits = [0] + [(byte >> i) & 1 for i in range(8)] + [1]

    def level(t):
        k = int(t // tx_bit_ns)
        return bits[k] if 0 <= k < len(bits) else 1

    if level(rx_bit_ns / 2) != 0:
        return None
    value = 0
    for i in range(8):
        value |= level(rx_bit_ns / 2 + (i + 1) * rx_bit_ns) << i
    return value, level(rx_bit_ns / 2 + 9 * rx_bit_ns) == 0
