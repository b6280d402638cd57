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

/* The calibration's divisions, done once (sensor_convert.h). */
static km_conv_t s_conv;

void km_hal_sensors_init(void)
{
    km_conv_prepare(&km_board_config, &s_conv);
    km_adc_start();
}

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
    if (km_conv_at_rail(cfg, raw[ADC_CH_NTC])) {
        faults |= KM_FAULT_TEMPERATURE;
    }

    out->position = km_conv_fast_position(&s_conv, raw[ADC_CH_POT]);
    out->current_ma = km_conv_fast_current_ma(&s_conv, raw[ADC_CH_SHUNT]) * km_board_motor_direction();
    out->voltage_mv = km_conv_fast_voltage_mv(&s_conv, raw[ADC_CH_VSUPPLY]);
    out->temperature_c10 = km_conv_fast_temperature_c10(cfg, &s_conv, raw[ADC_CH_NTC]);
    out->faults = faults;
}
