/* Entry point of the simulated servo image (qemu-microbit): the application
 * is the same on every board. */
#include "km_app.h"

int main(void)
{
    km_app_run();
}
