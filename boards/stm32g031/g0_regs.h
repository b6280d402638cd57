/* SPDX-License-Identifier: Apache-2.0 */
/* STM32G031 registers and bits the board uses, from RM0444 rev. 5 (no vendor
 * headers); each block names its section. */
/* clang-format off: register maps aligned by hand, one address per line */
#ifndef G0_REGS_H
#define G0_REGS_H

#include "g0_core.h"

/* ---- FLASH (RM0444 §3.7), base 0x4002 2000 (§2.2.2 memory map) ---- */
#define FLASH_BASE_R 0x40022000u
#define FLASH_ACR G0_REG(FLASH_BASE_R + 0x00u)
#define FLASH_KEYR G0_REG(FLASH_BASE_R + 0x08u)
#define FLASH_SR G0_REG(FLASH_BASE_R + 0x10u)
#define FLASH_CR G0_REG(FLASH_BASE_R + 0x14u)
#define FLASH_ECCR G0_REG(FLASH_BASE_R + 0x18u)
#define FLASH_ACR_LATENCY_MASK 7u /* §3.7.1 bits 2:0 */
#define FLASH_ACR_PRFTEN (1u << 8)
#define FLASH_ACR_ICEN (1u << 9)
#define FLASH_KEY1 0x45670123u /* §3.3.6 unlock sequence */
#define FLASH_KEY2 0xCDEF89ABu
#define FLASH_SR_EOP (1u << 0) /* §3.7.4 */
#define FLASH_SR_OPERR (1u << 1)
#define FLASH_SR_PROGERR (1u << 3)
#define FLASH_SR_WRPERR (1u << 4)
#define FLASH_SR_PGAERR (1u << 5)
#define FLASH_SR_SIZERR (1u << 6)
#define FLASH_SR_PGSERR (1u << 7)
#define FLASH_SR_MISSERR (1u << 8)
#define FLASH_SR_FASTERR (1u << 9)
#define FLASH_SR_RDERR (1u << 14)
#define FLASH_SR_OPTVERR (1u << 15)
#define FLASH_SR_BSY1 (1u << 16)
#define FLASH_SR_CFGBSY (1u << 18)
#define FLASH_SR_ERRORS                                                                        \
    (FLASH_SR_OPERR | FLASH_SR_PROGERR | FLASH_SR_WRPERR | FLASH_SR_PGAERR | FLASH_SR_SIZERR | \
     FLASH_SR_PGSERR | FLASH_SR_MISSERR | FLASH_SR_FASTERR | FLASH_SR_RDERR | FLASH_SR_OPTVERR)
#define FLASH_CR_PG (1u << 0) /* §3.7.5 */
#define FLASH_CR_PER (1u << 1)
#define FLASH_CR_PNB_SHIFT 3u
#define FLASH_CR_PNB_MASK (0x3FFu << 3) /* PNB[12:3], 10 bits (SVD; 32 pages here) */
#define FLASH_CR_STRT (1u << 16)
#define FLASH_CR_EOPIE (1u << 24) /* EOP is only flagged with EOPIE set */
#define FLASH_CR_LOCK (1u << 31)
#define FLASH_ECCR_ECCC (1u << 30) /* §3.7.6 single error corrected */
#define FLASH_ECCR_ECCD (1u << 31) /* double error detected (raises NMI) */
#define FLASH_MAIN_BASE 0x08000000u
#define FLASH_PAGE_SIZE 2048u

/* ---- RCC (RM0444 §5.4), base 0x4002 1000 ---- */
#define RCC_BASE_R 0x40021000u
#define RCC_CR G0_REG(RCC_BASE_R + 0x00u)
#define RCC_CFGR G0_REG(RCC_BASE_R + 0x08u)
#define RCC_PLLCFGR G0_REG(RCC_BASE_R + 0x0Cu)
#define RCC_IOPENR G0_REG(RCC_BASE_R + 0x34u)
#define RCC_AHBENR G0_REG(RCC_BASE_R + 0x38u)
#define RCC_APBENR1 G0_REG(RCC_BASE_R + 0x3Cu)
#define RCC_APBENR2 G0_REG(RCC_BASE_R + 0x40u)
#define RCC_CSR G0_REG(RCC_BASE_R + 0x60u)
#define RCC_CR_HSION (1u << 8) /* §5.4.1 */
#define RCC_CR_HSIRDY (1u << 10)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_CFGR_SW_MASK 7u /* §5.4.3 */
#define RCC_CFGR_SW_PLLRCLK 2u
#define RCC_CFGR_SWS_SHIFT 3u
#define RCC_PLLCFGR_SRC_HSI16 2u /* §5.4.4 bits 1:0 */
#define RCC_PLLCFGR_M_SHIFT 4u   /* M = field + 1 */
#define RCC_PLLCFGR_N_SHIFT 8u   /* N = field (8..86) */
#define RCC_PLLCFGR_REN (1u << 28)
#define RCC_PLLCFGR_R_SHIFT 29u    /* R = field + 1 (field >= 1) */
#define RCC_IOPENR_GPIOA (1u << 0) /* §5.4.13 */
#define RCC_IOPENR_GPIOB (1u << 1)
#define RCC_AHBENR_DMA1 (1u << 0)  /* §5.4.14 */
#define RCC_APBENR1_TIM2 (1u << 0) /* §5.4.15 */
#define RCC_APBENR1_TIM3 (1u << 1)
#define RCC_APBENR2_USART1 (1u << 14) /* §5.4.16 */
#define RCC_APBENR2_ADC (1u << 20)
/* RCC_CSR (§5.4) reset flags: sticky until RMVF; every internal reset also
 * sets PINRSTF (§5.1.2). */
#define RCC_CSR_RMVF (1u << 23)     /* write 1: clear every flag below */
#define RCC_CSR_OBLRSTF (1u << 25)  /* option byte loader (OBL_LAUNCH) */
#define RCC_CSR_PINRSTF (1u << 26)  /* NRST low (and every internal reset) */
#define RCC_CSR_PWRRSTF (1u << 27)  /* BOR or POR/PDR: supply below threshold */
#define RCC_CSR_SFTRSTF (1u << 28)  /* AIRCR.SYSRESETREQ */
#define RCC_CSR_IWDGRSTF (1u << 29) /* independent watchdog */
#define RCC_CSR_WWDGRSTF (1u << 30) /* window watchdog */
#define RCC_CSR_LPWRRSTF (1u << 31) /* Stop/Standby/Shutdown entry with nRST_* option */
#define RCC_CSR_RESET_FLAGS                                                                     \
    (RCC_CSR_OBLRSTF | RCC_CSR_PINRSTF | RCC_CSR_PWRRSTF | RCC_CSR_SFTRSTF | RCC_CSR_IWDGRSTF | \
     RCC_CSR_WWDGRSTF | RCC_CSR_LPWRRSTF)

/* ---- GPIO (RM0444 §7.4), IOPORT bus 0x5000 0000 ---- */
#define GPIOA_BASE_R 0x50000000u
#define GPIOB_BASE_R 0x50000400u
#define GPIO_MODER(p) G0_REG_AT((p), 0x00u)
#define GPIO_OTYPER(p) G0_REG_AT((p), 0x04u)
#define GPIO_OSPEEDR(p) G0_REG_AT((p), 0x08u)
#define GPIO_PUPDR(p) G0_REG_AT((p), 0x0Cu)
#define GPIO_BSRR(p) G0_REG_AT((p), 0x18u)
#define GPIO_AFR(p, n) G0_REG_AT((p), 0x20u + 4u * (n)) /* AFRL, AFRH */
#define GPIO_BRR(p) G0_REG_AT((p), 0x28u)

/* ---- USART1 (RM0444 §33.8), base 0x4001 3800 ---- */
#define USART1_BASE_R 0x40013800u
#define USART1_CR1 G0_REG(USART1_BASE_R + 0x00u)
#define USART1_CR2 G0_REG(USART1_BASE_R + 0x04u)
#define USART1_CR3 G0_REG(USART1_BASE_R + 0x08u)
#define USART1_BRR G0_REG(USART1_BASE_R + 0x0Cu)
#define USART1_ISR G0_REG(USART1_BASE_R + 0x1Cu)
#define USART1_ICR G0_REG(USART1_BASE_R + 0x20u)
#define USART1_RDR G0_REG(USART1_BASE_R + 0x24u)
#define USART1_TDR G0_REG(USART1_BASE_R + 0x28u)
#define USART_CR1_UE (1u << 0) /* §33.8.1 (FIFO disabled) */
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TCIE (1u << 6)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR3_EIE (1u << 0) /* §33.8.3 */
#define USART_CR3_HDSEL (1u << 3)
#define USART_ISR_PE (1u << 0) /* §33.8.9 */
#define USART_ISR_FE (1u << 1)
#define USART_ISR_NE (1u << 2)
#define USART_ISR_ORE (1u << 3)
#define USART_ISR_RXNE (1u << 5)
#define USART_ISR_TC (1u << 6)
#define USART_ISR_TXE (1u << 7)
#define USART_ICR_PECF (1u << 0) /* §33.8.10 */
#define USART_ICR_FECF (1u << 1)
#define USART_ICR_NECF (1u << 2)
#define USART_ICR_ORECF (1u << 3)
#define USART_ICR_TCCF (1u << 6)

/* ---- General-purpose timers TIM2/TIM3 (RM0444 §22.4) ---- */
#define TIM2_BASE_R 0x40000000u
#define TIM3_BASE_R 0x40000400u
#define TIM_CR1(t) G0_REG_AT((t), 0x00u)
#define TIM_DIER(t) G0_REG_AT((t), 0x0Cu)
#define TIM_SR(t) G0_REG_AT((t), 0x10u)
#define TIM_EGR(t) G0_REG_AT((t), 0x14u)
#define TIM_CCMR1(t) G0_REG_AT((t), 0x18u)
#define TIM_CCER(t) G0_REG_AT((t), 0x20u)
#define TIM_CNT(t) G0_REG_AT((t) + 0x24u, 0u) /* by its own address: one literal on the hot paths */
#define TIM_PSC(t) G0_REG_AT((t), 0x28u)
#define TIM_ARR(t) G0_REG_AT((t), 0x2Cu)
#define TIM_CCR1(t) G0_REG_AT((t), 0x34u)
#define TIM_CCR2(t) G0_REG_AT((t), 0x38u)
#define TIM_CR1_CEN (1u << 0) /* §22.4.1 */
#define TIM_CR1_ARPE (1u << 7)
#define TIM_DIER_CC1IE (1u << 1) /* §22.4.4 */
#define TIM_SR_CC1IF (1u << 1)   /* §22.4.5 (rc_w0) */
#define TIM_EGR_UG (1u << 0)     /* §22.4.6 */
#define TIM_EGR_CC1G (1u << 1)
#define TIM_CCMR1_OC1PE (1u << 3) /* §22.4.7 output compare mode */
#define TIM_CCMR1_OC1M_PWM1 (6u << 4)
#define TIM_CCMR1_OC2PE (1u << 11)
#define TIM_CCMR1_OC2M_PWM1 (6u << 12)
#define TIM_CCER_CC1E (1u << 0) /* §22.4.9 */
#define TIM_CCER_CC2E (1u << 4)

/* ---- ADC (RM0444 §15.12), base 0x4001 2400 ---- */
#define ADC_BASE_R 0x40012400u
#define ADC_ISR G0_REG(ADC_BASE_R + 0x00u)
#define ADC_CR G0_REG(ADC_BASE_R + 0x08u)
#define ADC_CFGR1 G0_REG(ADC_BASE_R + 0x0Cu)
#define ADC_CFGR2 G0_REG(ADC_BASE_R + 0x10u)
#define ADC_SMPR G0_REG(ADC_BASE_R + 0x14u)
#define ADC_CHSELR G0_REG(ADC_BASE_R + 0x28u)
#define ADC_DR G0_REG(ADC_BASE_R + 0x40u)
#define ADC_ISR_ADRDY (1u << 0) /* §15.12.1 */
#define ADC_ISR_EOCAL (1u << 11)
#define ADC_ISR_CCRDY (1u << 13)
#define ADC_CR_ADEN (1u << 0) /* §15.12.3 */
#define ADC_CR_ADSTART (1u << 2)
#define ADC_CR_ADVREGEN (1u << 28)
#define ADC_CR_ADCAL (1u << 31)
#define ADC_CFGR1_DMAEN (1u << 0)  /* §15.12.4 */
#define ADC_CFGR1_DMACFG (1u << 1) /* circular DMA mode */
#define ADC_CFGR1_OVRMOD (1u << 12)
#define ADC_CFGR1_CONT (1u << 13)
#define ADC_CFGR2_OVSE (1u << 0) /* §15.12.5 */
#define ADC_CFGR2_OVSR_SHIFT 2u
#define ADC_CFGR2_OVSS_SHIFT 5u
#define ADC_CFGR2_CKMODE_PCLK2 (1u << 30)
#define ADC_SMPR_SMP1_160_5 7u /* §15.12.6 160.5 ADC cycles */

/* ---- DMA1 channel 1 (RM0444 §10.6) and DMAMUX (§11.6) ---- */
#define DMA1_BASE_R 0x40020000u
#define DMA1_CCR1 G0_REG(DMA1_BASE_R + 0x08u)
#define DMA1_CNDTR1 G0_REG(DMA1_BASE_R + 0x0Cu)
#define DMA1_CPAR1 G0_REG(DMA1_BASE_R + 0x10u)
#define DMA1_CMAR1 G0_REG(DMA1_BASE_R + 0x14u)
#define DMA_CCR_EN (1u << 0)
#define DMA_CCR_CIRC (1u << 5)
#define DMA_CCR_MINC (1u << 7)
#define DMA_CCR_PSIZE_16 (1u << 8)
#define DMA_CCR_MSIZE_16 (1u << 10)
#define DMAMUX_C0CR G0_REG(0x40020800u) /* channel 0 feeds DMA1 channel 1 */
#define DMAMUX_REQ_ADC 5u               /* §11.3.2 table 59 */

/* ---- IWDG (RM0444 §27.7), base 0x4000 3000 ---- */
#define IWDG_BASE_R 0x40003000u
#define IWDG_KR G0_REG(IWDG_BASE_R + 0x00u)
#define IWDG_PR G0_REG(IWDG_BASE_R + 0x04u)
#define IWDG_RLR G0_REG(IWDG_BASE_R + 0x08u)
#define IWDG_SR G0_REG(IWDG_BASE_R + 0x0Cu)
#define IWDG_KEY_UNLOCK 0x5555u
#define IWDG_KEY_START 0xCCCCu
#define IWDG_KEY_KICK 0xAAAAu

/* ---- Device electronic signature (RM0444 §40.1): 96-bit unique ID ---- */
#define UID_BASE_R 0x1FFF7590u

#endif
