/* CRC-32, bitwise: no 1 KiB table in the M0 image; records are short and
 * checked only at mount and after a write, so speed does not matter. */
#include "km_crc32.h"

uint32_t km_crc32(uint32_t crc, const uint8_t *data, uint32_t n)
{
    crc = ~crc;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= data[i];
        for (unsigned b = 0; b < 8u; b++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}
