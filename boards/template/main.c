/* SPDX-License-Identifier: Apache-2.0 */
/* The servo firmware's entry: the application is the same on every board. */
#include "km_app.h"

/* Everything else happens in the app (km_app.h): hal init, store, bus. */
int main(void)
{
    km_app_run();
}
