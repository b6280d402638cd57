/* SPDX-License-Identifier: Apache-2.0 */
/* CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320): guards every store record. */
#ifndef KM_CRC32_H
#define KM_CRC32_H

#include <stdint.h>

/* Continue a CRC over n more bytes; start with crc = 0. */
uint32_t km_crc32(uint32_t crc, const uint8_t *data, uint32_t n);

#endif
