// Client-side RAM of the link core on the Cortex-M4: one Link and the
// workspace its device configuration needs (4 x 1 KiB stream window), as
// static objects whose sizes bench/run_link.sh reads from the object file.
#include "vds/link/link.h"

namespace {
constexpr vds::link::LinkConfig kConfig = vds::link::device_config(1);
constexpr size_t kWorkspace = vds::link::link_workspace_size(kConfig);
static_assert(kConfig.channels[vds::link::channel::kStream].rx_bytes == 4096, "a 4 x 1 KiB window");
static_assert(sizeof(vds::link::Link) + kWorkspace <= 8192, "client link RAM must stay within 8 KiB");
}  // namespace

vds::link::Link g_link;
alignas(8) uint8_t g_link_workspace[kWorkspace];

// Touches both so the objects are kept; the firmware's init looks like this.
extern "C" int link_ram_init() {
  vds::Arena arena(g_link_workspace, sizeof g_link_workspace);
  return static_cast<int>(g_link.init(kConfig, arena));
}
