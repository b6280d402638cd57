/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_sensors for the STM32G031 board: the latest ADC set converted with
 * the product calibration, plus the 0x35 sensor fault bits:
 *  - position (bit 5): wiper at a rail (open wiper, broken track or supply);
 *  - current (bit 4): amplifier output at the top rail (saturated or open);
 *  - voltage (bit 3): divider at a rail (we are running, so it cannot be 0);
 *  - temperature (bit 2): NTC at a rail (open: pulled up; short: 0). */
#include "km_hal_sensors.h"

#include "adc.h"
#include "board_config.h"
#include "km_board.h"
#include "sensor_convert.h"

/* The NTC segment of the last reading (km_conv_fast_temperature_c10). */
static uint8_t s_ntc_at;

/* The NTC converted on one reading in 4, from the first (heat is slow: the
 * temperature's protection and checks time 500 ms and 3 s; the reading is
 * at most 3 ms old). The main loop's idle flash work takes another of the
 * 4 ticks (docs/benchmarks.md "Control tick"). */
#define PRV_NTC_EVERY_MASK 3u
static uint32_t s_reads;
static int32_t s_temperature_c10;
static bool s_ntc_at_rail;

void km_hal_sensors_init(void)
{
    s_reads = 0u;
    km_adc_start();
}

/* The latest ADC set in engineering units and the rail fault bits; the NTC on one call in 4. */
void km_hal_sensors_read(km_sensors_t *out)
{
    const km_board_config_t *cfg = &km_board_config;
    uint16_t raw[ADC_CHANNELS];
    km_adc_latest(raw);

    uint8_t faults = 0u;
    if (km_conv_at_rail(cfg, raw[ADC_CH_POT])) {
        faults |= KM_FAULT_POSITION;
    }
    if (raw[ADC_CH_SHUNT] >= KM_ADC_FULL_SCALE - cfg->rail_margin) {
        faults |= KM_FAULT_CURRENT;
    }
    if (km_conv_at_rail(cfg, raw[ADC_CH_VSUPPLY])) {
        faults |= KM_FAULT_VOLTAGE;
    }
    if ((s_reads++ & PRV_NTC_EVERY_MASK) == 0u) {
        s_ntc_at_rail = km_conv_at_rail(cfg, raw[ADC_CH_NTC]);
        s_temperature_c10 = km_conv_fast_temperature_c10(cfg, &km_board_conv, &s_ntc_at, raw[ADC_CH_NTC]);
    }
    if (s_ntc_at_rail) {
        faults |= KM_FAULT_TEMPERATURE;
    }

    out->position = km_conv_fast_position(&km_board_conv, raw[ADC_CH_POT]);
    out->current_ma = km_conv_fast_current_ma(&km_board_conv, raw[ADC_CH_SHUNT]) * km_board_motor_direction();
    out->voltage_mv = km_conv_fast_voltage_mv(&km_board_conv, raw[ADC_CH_VSUPPLY]);
    out->temperature_c10 = s_temperature_c10;
    out->faults = faults;
}
