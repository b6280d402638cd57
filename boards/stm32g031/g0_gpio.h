/* SPDX-License-Identifier: Apache-2.0 */
/* Tiny GPIO helpers over the RM0444 §7.4 registers: one call per pin role. */
#ifndef G0_GPIO_H
#define G0_GPIO_H

#include "g0_regs.h"

#define G0_GPIO_MODE_INPUT 0u
#define G0_GPIO_MODE_OUTPUT 1u
#define G0_GPIO_MODE_AF 2u
#define G0_GPIO_MODE_ANALOG 3u

static inline void g0_gpio_mode(uint32_t port, uint32_t pin, uint32_t mode)
{
    GPIO_MODER(port) = (GPIO_MODER(port) & ~(3u << (2u * pin))) | (mode << (2u * pin));
}

static inline void g0_gpio_af(uint32_t port, uint32_t pin, uint32_t af)
{
    uint32_t shift = 4u * (pin & 7u);
    GPIO_AFR(port, pin >> 3) = (GPIO_AFR(port, pin >> 3) & ~(0xFu << shift)) | (af << shift);
    g0_gpio_mode(port, pin, G0_GPIO_MODE_AF);
}

static inline void g0_gpio_open_drain_pullup(uint32_t port, uint32_t pin)
{
    GPIO_OTYPER(port) |= 1u << pin;
    GPIO_PUPDR(port) = (GPIO_PUPDR(port) & ~(3u << (2u * pin))) | (1u << (2u * pin));
}

static inline void g0_gpio_fast(uint32_t port, uint32_t pin)
{
    GPIO_OSPEEDR(port) |= 3u << (2u * pin);
}

static inline void g0_gpio_set(uint32_t port, uint32_t pin)
{
    GPIO_BSRR(port) = 1u << pin;
}
static inline void g0_gpio_clear(uint32_t port, uint32_t pin)
{
    GPIO_BRR(port) = 1u << pin;
}

#endif
