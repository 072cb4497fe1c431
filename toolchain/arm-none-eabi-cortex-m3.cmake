# Cortex-M3 client build: same rules as the M4 build, no DSP instructions.
set(VDS_ARM_CPU cortex-m3)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
