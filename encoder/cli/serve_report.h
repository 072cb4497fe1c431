// What `vds serve` and `vds play` print of a link session: the link's
// figures, every frame the client reported and its statistics, and the
// client's end-of-stream report, checked against the stream.
#pragma once
#include <string>

#include "commands.h"
#include "vds/link/backend.h"
#include "vds/link/serve.h"

namespace vds::cli {

// A link failure as the verb's failure (a bad --link is a usage error).
Failure backend_failure(const link::BackendError& e);
void print_serve_report(const std::string& name, const link::ServeOptions& o, const link::ServeReport& r);
// Throws Failure unless the client reported the whole stream (or a prefix
// it asked for) intact.
void check_serve_report(const link::ServeReport& r);

}  // namespace vds::cli
