/* SPDX-License-Identifier: Apache-2.0 */
/* Simulated boards (qemu-microbit, host-sim): the hal motor and sensors
 * contracts over the simulated plant. The plant advances by the real elapsed
 * tick time at every sensor read, so motion is what the motor commands
 * produce, never faked; with the bridge free the shaft stays where it is. */
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_time.h"
#include "km_plant.h"
#include "km_app.h"
#include "km_sim_board.h"
#include "km_turn_counter.h"

/* The plant advances in steps of at most KM_SIM_STEP_US, so a read after a
 * starved host (a loaded CI machine) catches the plant up to the firmware's
 * clock with the scenario played between steps: plant time and firmware time
 * stay one clock. Only a pause longer than KM_SIM_CATCHUP_US (a debugger, a
 * suspended host) drops the excess. */
#define KM_SIM_STEP_US 100000u
#define KM_SIM_CATCHUP_US 10000000u

static km_plant_t s_plant;
static km_plant_input_t s_input = {.bridge = KM_PLANT_COAST, .pwm = 0, .ext_torque_unm = 0};
static uint32_t s_last_tick;
static uint32_t s_us_per_tick_q16;
static bool s_encoder;
static km_turn_counter_t s_turns; /* the encoder product's multi-turn count */
static km_scn_player_t s_scenario;
/* The encoder product's plant: the default motor with no pot and no end
 * stops, as the control tests build it (tests/unit/control/test_control_motor.c).
 * The plant keeps a pointer, so it lives here. */
static km_plant_config_t s_encoder_config;
#ifdef KM_SIM_PLANT_IDEAL
static const km_plant_config_t *s_plant_config = &km_plant_ideal_config;
#else
static const km_plant_config_t *s_plant_config = &km_plant_realistic_config;
#endif

void km_sim_board_select_plant(const km_plant_config_t *cfg)
{
    s_plant_config = cfg;
}

void km_hal_motor_init(void)
{
    s_input.bridge = KM_PLANT_COAST;
    s_input.pwm = 0;
}

void km_hal_motor_drive(int16_t pwm)
{
    if (pwm > KM_MOTOR_PWM_MAX) {
        pwm = KM_MOTOR_PWM_MAX;
    } else if (pwm < -KM_MOTOR_PWM_MAX) {
        pwm = -KM_MOTOR_PWM_MAX;
    }
    s_input.bridge = KM_PLANT_DRIVE;
    s_input.pwm = pwm;
}

void km_hal_motor_free(void)
{
    s_input.bridge = KM_PLANT_COAST;
    s_input.pwm = 0;
}

void km_hal_motor_brake(void)
{
    s_input.bridge = KM_PLANT_BRAKE;
    s_input.pwm = 0;
}

void km_hal_sensors_init(void)
{
    /* The plant is physics: at power-on it starts at rest at 0; after a
     * restart the board hands back the shaft as the last boot left it. A
     * pot servo reads its shaft as it is; the encoder product reads a
     * single-turn absolute encoder and counts turns in RAM, so after a
     * restart its 0x46 is the angle within one turn, [0, 360.0) deg, before
     * the zero offsets (docs/protocol.md §5.3, §6; docs/protocol-decisions.md). */
    s_encoder = km_board_product()->variant == KM_VARIANT_ENCODER;
    if (s_encoder) {
        s_encoder_config = *s_plant_config;
        s_encoder_config.pot_travel_ddeg = 0;
        s_encoder_config.endstop_ddeg = 0;
        (void)km_plant_init(&s_plant, &s_encoder_config);
    } else {
        (void)km_plant_init(&s_plant, s_plant_config);
    }
    km_plant_physics_t kept;
    if (km_sim_board_recall(&kept)) {
        km_plant_set_physics(&s_plant, &kept);
    }
    uint32_t n = 0;
    const km_scn_event_t *ev = km_sim_board_scenario(&n);
    km_scn_start(&s_scenario, ev, n);
    km_scn_play(&s_scenario, &s_plant, &s_input); /* what was due before a restart, at once */
    km_turn_counter_init(&s_turns, (uint16_t)KM_PLANT_ENCODER_COUNTS, km_plant_encoder_counts(&s_plant));
    s_us_per_tick_q16 = (uint32_t)((1000000ull << 16) / km_hal_time_tick_hz());
    s_last_tick = km_hal_time_now();
}

void km_hal_sensors_read(km_sensors_t *out)
{
    const uint32_t now = km_hal_time_now();
    uint32_t dt_us = (uint32_t)(((uint64_t)(now - s_last_tick) * s_us_per_tick_q16) >> 16);
    if (dt_us > KM_SIM_CATCHUP_US) {
        dt_us = KM_SIM_CATCHUP_US;
    }
    s_last_tick = now;
    do {
        const uint32_t step_us = dt_us > KM_SIM_STEP_US ? KM_SIM_STEP_US : dt_us;
        km_plant_step(&s_plant, &s_input, step_us);
        km_scn_play(&s_scenario, &s_plant, &s_input);
        dt_us -= step_us;
    } while (dt_us > 0u);
    km_plant_physics_t physics;
    km_plant_get_physics(&s_plant, &physics);
    km_sim_board_keep(&physics);
    out->position = s_encoder ? km_turn_counter_update(&s_turns, km_plant_encoder_counts(&s_plant))
                              : km_plant_position_ddeg(&s_plant);
    out->current_ma = km_plant_current_ma(&s_plant);
    out->voltage_mv = km_plant_voltage_mv(&s_plant);
    out->temperature_c10 = km_plant_temp_dc(&s_plant);
    out->faults = 0; /* the simulated sensors are sound unless a test injects a fault */
}

/* One scenario event applied now (km_sim_board.h). */
void km_sim_board_inject(uint32_t key, int32_t value)
{
    const km_scn_event_t now = {.t_ms = 0u, .key = key, .value = value};
    km_scn_player_t one;
    km_scn_start(&one, &now, 1u);
    km_scn_play(&one, &s_plant, &s_input);
}

km_plant_t *km_sim_board_plant(void)
{
    return &s_plant;
}

/* The app's main loop with this emulated bus's floors (km_sim_board.h). */
_Noreturn void km_sim_board_run(uint32_t gap_floor_us, uint32_t slot_floor_us)
{
    km_app_init();
    km_app_set_bus_floors(gap_floor_us, slot_floor_us);
    for (;;) {
        km_app_poll();
    }
}
