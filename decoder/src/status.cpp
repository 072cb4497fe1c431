// vds client library: names for the status codes (see status.h).
#include "vds/status.h"

#include "vds/config.h"

namespace vds {

const char* status_name(Status s) {
#if VDS_CONFIG_STATUS_NAMES
  switch (s) {
    case Status::ok: return "ok";
    case Status::more_input: return "more input needed";
    case Status::truncated: return "truncated input";
    case Status::workspace_too_small: return "workspace too small";
    case Status::malformed: return "malformed data";
    case Status::unsupported_version: return "unsupported version";
    case Status::unsupported_feature: return "unsupported feature";
    case Status::aborted: return "aborted by callback";
    case Status::bad_crc: return "CRC mismatch";
    case Status::invalid_argument: return "invalid argument";
    case Status::output_too_small: return "output buffer too small";
    case Status::io_error: return "read callback failed";
  }
  return "unknown status";
#else
  (void)s;
  return "";
#endif
}

}  // namespace vds
