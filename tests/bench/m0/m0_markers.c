/* SPDX-License-Identifier: Apache-2.0 */
/* The count markers of the bench-m0 images (tools/bench/bench-m0): one `bx lr`
 * each, in assembly so that no compiler can merge, inline or pad them. The
 * tool counts the executed instructions from the entry of m0_begin to the
 * entry of m0_end; regions nest.
 *
 * The validation regions, whole in assembly so that no compiler schedules
 * anything into them: m0_region_empty counts 1 (its bl m0_end),
 * m0_region_loop1000 counts 2,002: ldr r0, =1000, then 1,000 x (subs,
 * bne), then the bl m0_end. */
void m0_begin(void);
void m0_end(void);
void m0_region_empty(void);
void m0_region_loop1000(void);

__asm__(".syntax unified\n"
        ".thumb\n"
        ".section .text.m0_begin,\"ax\",%progbits\n"
        ".balign 2\n"
        ".global m0_begin\n"
        ".thumb_func\n"
        ".type m0_begin, %function\n"
        "m0_begin:\n"
        "  bx lr\n"
        ".size m0_begin, .-m0_begin\n"
        ".section .text.m0_end,\"ax\",%progbits\n"
        ".balign 2\n"
        ".global m0_end\n"
        ".thumb_func\n"
        ".type m0_end, %function\n"
        "m0_end:\n"
        "  bx lr\n"
        ".size m0_end, .-m0_end\n"
        ".section .text.m0_region_empty,\"ax\",%progbits\n"
        ".balign 2\n"
        ".global m0_region_empty\n"
        ".thumb_func\n"
        ".type m0_region_empty, %function\n"
        "m0_region_empty:\n"
        "  push {r4, lr}\n"
        "  bl m0_begin\n"
        "  bl m0_end\n"
        "  pop {r4, pc}\n"
        ".size m0_region_empty, .-m0_region_empty\n"
        ".section .text.m0_region_loop1000,\"ax\",%progbits\n"
        ".balign 4\n"
        ".global m0_region_loop1000\n"
        ".thumb_func\n"
        ".type m0_region_loop1000, %function\n"
        "m0_region_loop1000:\n"
        "  push {r4, lr}\n"
        "  bl m0_begin\n"
        "  ldr r0, =1000\n"
        "1:\n"
        "  subs r0, r0, #1\n"
        "  bne 1b\n"
        "  bl m0_end\n"
        "  pop {r4, pc}\n"
        ".ltorg\n"
        ".size m0_region_loop1000, .-m0_region_loop1000\n"
        ".text\n"
        ".syntax divided\n");
