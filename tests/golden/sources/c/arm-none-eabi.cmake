# arm-none-eabi.cmake - CMake toolchain file for a Cortex-M4F (single-precision FPU),
# written by eomgen 0.1.0 next to the model 'pendulum_kane'. Do not edit: copy it instead.
#
#   cmake -S . -B build-arm -DCMAKE_TOOLCHAIN_FILE=arm-none-eabi.cmake
#   cmake --build build-arm          -> libpendulum_kane_model.a, -Os (default build type
#                                       MinSizeRel); the simulator is not built
#
# Another toolchain prefix: -DARM_NONE_EABI_PREFIX=/opt/gcc-arm/bin/arm-none-eabi-
# Another core: -DARM_CPU_FLAGS="-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard"
# Generate with real="float" for an FPU without double (the M4F): double
# arithmetic there is software emulation.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(ARM_NONE_EABI_PREFIX "arm-none-eabi-" CACHE STRING "Prefix of the GNU Arm Embedded tools")
set(ARM_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard"
    CACHE STRING "Target CPU flags")

set(CMAKE_C_COMPILER "${ARM_NONE_EABI_PREFIX}gcc")
set(CMAKE_AR "${ARM_NONE_EABI_PREFIX}ar" CACHE FILEPATH "archiver")
set(CMAKE_RANLIB "${ARM_NONE_EABI_PREFIX}ranlib" CACHE FILEPATH "ranlib")
set(CMAKE_SIZE "${ARM_NONE_EABI_PREFIX}size" CACHE FILEPATH "size tool")
# no OS to run a test executable on: check the compiler with a static library
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CMAKE_C_FLAGS_INIT "${ARM_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
