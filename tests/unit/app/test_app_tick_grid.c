/* SPDX-License-Identifier: Apache-2.0 */
/* The control tick's time step (firmware/app/km_app.c prv_next_tick,
 * docs/benchmarks.md "Control tick"): the app runs km_control_step on a
 * fixed 1 ms grid and hands it the grid's step, not the time between two
 * wake-ups; a sampled controller assumes its period, so wake-ups that
 * jitter by a few us give exactly 1000 us every tick, and a tick half a
 * period late moves the grid and gets the grid time that passed. The real
 * app and control step run on the fake board (tests/support/km_fake_hal.c)
 * with a jittered 1 kHz SysTick and hal calls that take no time, so each
 * tick's time is its wake-up's; the linker's --wrap puts a recorder of
 * each step's dt in front of the real km_control_step. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_control.h"
#include "km_fake_hal.h"

#define PRV_SEEN_MAX 512u
#define PRV_PERIOD_US KM_CONTROL_TICK_US

/* Each control step the app ran: its dt and the virtual time it ran at. */
static struct {
    unsigned n;
    uint32_t dt_us[PRV_SEEN_MAX];
    uint32_t at[PRV_SEEN_MAX];
} s_seen;

void __real_km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p,
                            uint32_t dt_us, km_live_t *live, km_bridge_t *bridge);
void __wrap_km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p,
                            uint32_t dt_us, km_live_t *live, km_bridge_t *bridge);

/* Records the step's dt and time, then runs the real control step. */
void __wrap_km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p,
                            uint32_t dt_us, km_live_t *live, km_bridge_t *bridge)
{
    if (s_seen.n < PRV_SEEN_MAX) {
        s_seen.dt_us[s_seen.n] = dt_us;
        s_seen.at[s_seen.n] = kf_world.now;
        s_seen.n++;
    }
    __real_km_control_step(c, in, p, dt_us, live, bridge);
}

/* How late (us) the SysTick's wake-up at each whole ms comes, in turn:
 * wake-ups 1000 +- up to 9 us apart. */
static const uint16_t s_late_us[] = {0, 6, 2, 9, 1, 7, 3, 8, 5, 4, 9, 0};

/* The app booted at a whole ms with free hal calls and the jittered
 * SysTick; returns the boot time, the grid's first point. */
static uint32_t boot_on_jittered_systick(void)
{
    kf_power_on();
    kf_world.cpu_ticks_per_call = 0u;
    kf_world.wake_late_us = s_late_us;
    kf_world.wake_late_n = sizeof s_late_us / sizeof s_late_us[0];
    kf_world.now = (kf_world.now / 1000u + 1u) * 1000u;
    const uint32_t t0 = kf_world.now;
    kf_boot(KM_RESET_POWER_ON);
    s_seen.n = 0u;
    return t0;
}

/* Wake-ups 1000 +- up to 9 us apart: every step is 1000 us, the first one
 * too, and each tick runs at its grid point's wake-up. */
static void test_jittered_wakeups_step_the_period(void **state)
{
    (void)state;
    const uint32_t t0 = boot_on_jittered_systick();
    assert_true(kf_run_until(t0 + 200000u));
    assert_false(kf_world.spun);
    assert_true(s_seen.n >= 199u);
    unsigned jittered = 0u;
    for (unsigned i = 0; i < s_seen.n; i++) {
        assert_int_equal(s_seen.dt_us[i], PRV_PERIOD_US);
        const uint32_t late = s_seen.at[i] - (t0 + i * PRV_PERIOD_US);
        assert_true(late < 10u); /* on its own grid point's wake-up */
        if (i > 0u && s_seen.at[i] - s_seen.at[i - 1u] != PRV_PERIOD_US) {
            jittered++;
        }
    }
    assert_true(jittered > s_seen.n / 2u); /* the wake-ups did jitter */
}

/* The main loop held for 2 ms (a long flash erase would): the late tick
 * moves the grid to 1/8 period before it and its step is the grid time
 * since the last tick's point; the ticks after it step 1000 us again on
 * the new grid. */
static void test_late_tick_rebases_and_steps_the_grid_time(void **state)
{
    (void)state;
    const uint32_t t0 = boot_on_jittered_systick();
    assert_true(kf_run_until(t0 + 20500u));
    const unsigned late_i = s_seen.n; /* the tick due at the wake-up the run stopped on */
    assert_true(late_i >= 20u);
    kf_world.now += 2000u; /* held: the next pass comes 2 ms after that wake-up */
    const uint32_t held_until = kf_world.now;
    assert_true(kf_run_until(held_until + 50000u));
    assert_false(kf_world.spun);
    assert_true(s_seen.n > late_i + 40u);

    for (unsigned i = 0; i < late_i; i++) {
        assert_int_equal(s_seen.dt_us[i], PRV_PERIOD_US);
    }
    assert_int_equal(s_seen.at[late_i], held_until);
    const uint32_t last_point = t0 + (late_i - 1u) * PRV_PERIOD_US;
    const uint32_t moved_point = held_until - PRV_PERIOD_US / 8u;
    assert_int_equal(s_seen.dt_us[late_i], moved_point - last_point);
    for (unsigned i = late_i + 1u; i < s_seen.n; i++) {
        assert_int_equal(s_seen.dt_us[i], PRV_PERIOD_US);
        const uint32_t late = s_seen.at[i] - (moved_point + (i - late_i) * PRV_PERIOD_US);
        assert_true(late < PRV_PERIOD_US / 2u); /* on the moved grid */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jittered_wakeups_step_the_period),
        cmocka_unit_test(test_late_tick_rebases_and_steps_the_grid_time),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
