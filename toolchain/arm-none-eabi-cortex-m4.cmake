# Cortex-M4 client build: arm-none-eabi-gcc (Debian gcc-arm-none-eabi) with
# newlib. Soft-float ABI on purpose: any float or double operation becomes an
# __aeabi_f*/__aeabi_d* call that the link check rejects.
set(VDS_ARM_CPU cortex-m4)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
