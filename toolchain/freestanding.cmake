# The rules of everything that runs on the client (decoder/, transport/core/),
# applied by the build on the host and on Cortex-M alike:
# freestanding, no exceptions, no RTTI, no thread-safe statics, warnings that
# catch silent float promotion. The link check in tests/ is the final judge
# (no float, heap, exception or libc symbol may be referenced).
set(VDS_FREESTANDING_FLAGS
  -ffreestanding
  -fno-exceptions
  -fno-rtti
  -fno-threadsafe-statics
  -fno-asynchronous-unwind-tables
  -Wall -Wextra -Wshadow -Wdouble-promotion -Wfloat-conversion 
  -Werror=double-promotion -Werror=float-conversion -Werror=return-type
)

function(vds_freestanding target)
  target_compile_options(${target} PRIVATE ${VDS_FREESTANDING_FLAGS})
endfunction()
