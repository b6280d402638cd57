# host-sim: native build, no CPU flags. TCP delivers bytes when the host
# schedules the program (see KM_APP_GAP_MIN_US in firmware/app/km_app.c).
add_compile_definitions(KM_APP_GAP_MIN_US=20000u)
