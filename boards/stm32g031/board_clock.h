/* SPDX-License-Identifier: Apache-2.0 */
/* Clock figures the drivers derive their dividers from (set in system.c). */
#ifndef BOARD_CLOCK_H
#define BOARD_CLOCK_H

#define BOARD_SYSCLK_HZ 64000000u
#define BOARD_PCLK_HZ 64000000u /* APB undivided */

#endif
