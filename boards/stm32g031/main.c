/* SPDX-License-Identifier: Apache-2.0 */
/* Entry point of the STM32G031 servo firmware: the application is the same
 * on every board; this board's drivers sit behind hal/. */
#include "km_app.h"

int main(void)
{
    km_app_run();
}
