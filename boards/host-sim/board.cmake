# host-sim: native build, no CPU flags. The UART's gap floor is a run-time
# option (--gap-floor-us, hs_main.c), not a build setting.
