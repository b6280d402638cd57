# SPDX-License-Identifier: Apache-2.0
# Fails a CTest entry with the message KM_MSG (cmake -DKM_MSG=... -P fail.cmake).
message(FATAL_ERROR "${KM_MSG}")
