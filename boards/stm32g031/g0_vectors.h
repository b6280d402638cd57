/* SPDX-License-Identifier: Apache-2.0 */
/* Handler declarations shared by the vector table (startup.c) and the drivers. */
#ifndef G0_VECTORS_H
#define G0_VECTORS_H
/* Initial SP, 15 core exceptions, 32 device IRQs: the RAM table (stm32g031_sections.ld). */
#define G0_VECTOR_COUNT 48u

void Reset_Handler(void);
void NMI_Handler(void);
void HardFault_Handler(void);
void SVC_Handler(void);
void PendSV_Handler(void);
void SysTick_Handler(void);
void TIM2_IRQHandler(void);
void USART1_IRQHandler(void);

#endif
