/* SPDX-License-Identifier: Apache-2.0 */
/* CRC-32 by nibbles (a 64-byte table), or bit by bit where flash is
 * shortest (KM_CRC32_BITWISE: the 32 KiB STM32G031F6's application store,
 * 68 B less, docs/footprint.md): the same CRC either way. */
#include "km_crc32.h"

#ifndef KM_CRC32_BITWISE
#define KM_CRC32_BITWISE 0
#endif

#define PRV_POLY 0xEDB88320u

#if KM_CRC32_BITWISE
/* Continue a CRC over n more bytes, one bit per step. */
uint32_t km_crc32(uint32_t crc, const uint8_t *data, uint32_t n)
{
    crc = ~crc;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= data[i];
        for (uint32_t k = 0; k < 8u; k++) {
            crc = (crc >> 1) ^ (PRV_POLY & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}
#else
static const uint32_t k_nibble[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
    PRV_POLY,    0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu, 0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};

/* Continue a CRC over n more bytes, one nibble per step. */
uint32_t km_crc32(uint32_t crc, const uint8_t *data, uint32_t n)
{
    crc = ~crc;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= data[i];
        crc = (crc >> 4) ^ k_nibble[crc & 15u];
        crc = (crc >> 4) ^ k_nibble[crc & 15u];
    }
    return ~crc;
}
#endif
