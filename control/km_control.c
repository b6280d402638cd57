/* Control interface and sensing (see km_control.h for what is not here yet). */
#include "km_control.h"

#include <string.h>

#define CONFIG_DIRECTION   0x04u
#define CONFIG_IDLE_BRAKE  0x02u
#define CONFIG_POWERON_BRAKE 0x01u

/* Speed is position change over a 20 ms window: at 0.1 deg resolution a
 * 1 ms difference would quantise speed to 100 deg/s steps. */
#define SPEED_WINDOW_US 20000u

static km_bridge_t prv_idle_output(const km_control_config_t *cfg, uint8_t brake_bit)
{
    km_bridge_t b = {(cfg->config & brake_bit) ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE, 0};
    return b;
}

void km_control_init(km_control_t *c, const km_control_config_t *cfg)
{
    memset(c, 0, sizeof *c);
    c->bridge = prv_idle_output(cfg, CONFIG_POWERON_BRAKE); /* §5.1 0x11 bit 0 */
}

void km_control_request(km_control_t *c, const km_request_t *req, const km_control_config_t *cfg)
{
    c->requests++;
    c->last_request = *req;
    if (req->kind == KM_REQ_TORQUE_SWITCH) {
        /* §5.4 0x64: 0 free, 1 brake damping; 2 and 3 need the position loop,
         * which is not here yet: the output stays at the idle setting. */
        if (req->u.u8 == 0u) {
            c->bridge.mode = KM_BRIDGE_FREE;
        } else if (req->u.u8 == 1u) {
            c->bridge.mode = KM_BRIDGE_BRAKE;
        } else {
            c->bridge = prv_idle_output(cfg, CONFIG_IDLE_BRAKE);
        }
    }
}

void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_config_t *cfg,
                     uint32_t dt_us, km_live_t *live, km_bridge_t *bridge)
{
    /* §5.1: reported position = sensor + level-1 + level-2 zero offsets, with
     * the sign flipped when 0x11 bit 2 makes counter-clockwise positive. */
    int32_t pos = in->position + cfg->zero_offset1 + cfg->zero_offset2;
    if (cfg->config & CONFIG_DIRECTION) {
        pos = -pos;
    }
    if (c->have_position) {
        c->speed_acc += pos - c->last_position;
        c->speed_us += dt_us;
        if (c->speed_us >= SPEED_WINDOW_US) {
            /* 0.1 deg per us -> deg/s: x 1e6 / 10. Clamped so the product
             * stays in 32 bits (M0 has no 64-bit divide instruction);
             * +-20000 x 0.1 deg in one window is far past any servo. */
            const int32_t acc = c->speed_acc > 20000 ? 20000 : (c->speed_acc < -20000 ? -20000 : c->speed_acc);
            c->speed_dps = (acc * 100000) / (int32_t)c->speed_us;
            c->speed_acc = 0;
            c->speed_us = 0;
        }
    }
    c->last_position = pos;
    c->have_position = true;

    memset(live, 0, sizeof *live);
    live->position = pos;
    live->speed = c->speed_dps;
    live->current = in->current_ma;
    live->pwm = c->bridge.mode == KM_BRIDGE_PWM ? (c->bridge.pwm < 0 ? -c->bridge.pwm : c->bridge.pwm) : 0;
    live->temperature = in->temperature_c10 / 10;
    live->voltage = in->voltage_mv;
    live->hw_faults = in->faults;
    *bridge = c->bridge;
}
