# SPDX-License-Identifier: Apache-2.0
# Adds a register to a copy of protocol/ the way docs/architecture.md
# "Adding a register" says, touching nothing else: copies every file of
# protocol/ into DEST unchanged, then appends one row to each .def file
# (rows.def and rows_doc.def, beside this script). The register's one hook
# is compiled beside the copy (km_hook_demo.c). Run by
# tests/protocol_extend.cmake: cmake -DSRC=protocol -DHERE=tests/extend -DDEST=... -P
file(GLOB sources ${SRC}/*.c ${SRC}/*.h ${SRC}/*.def)
file(REMOVE_RECURSE ${DEST})
file(COPY ${sources} DESTINATION ${DEST})
file(READ ${HERE}/rows.def row)
file(APPEND ${DEST}/km_registers.def "${row}")
file(READ ${HERE}/rows_doc.def row_doc)
file(APPEND ${DEST}/km_registers_doc.def "${row_doc}")
