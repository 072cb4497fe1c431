// `vds serve`: stream a file over a link to a client (docs/protocol.md).
// With --link loopback an in-process client receives it through the
// freestanding link core, verifies every chunk and sends its end-of-stream
// report back.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "serve_report.h"
#include "vds/enc/stream_writer.h"
#include "vds/link/backend.h"
#include "vds/link/serve.h"
#include "vds/status.h"

namespace vds::cli {
namespace {

struct ServeArgs {
  std::string stream;
  std::string link = "loopback";
  uint32_t baud = 115200;
  uint32_t timeout = 0;
  double ber = 0;
  double frame_loss = 0;
  uint64_t seed = 1;
  std::string crc_out;
  bool unpaced = false;
};

}  // namespace

Failure backend_failure(const link::BackendError& e) {
  return Failure(e.kind() == link::BackendError::Kind::bad_spec ? kExitUsage : kExitBadInput,
                 std::string(e.what()) + " [" + link::backend_error_kind_name(e.kind()) + "]");
}

void print_serve_report(const std::string& name, const link::ServeOptions& o, const link::ServeReport& r) {
  std::printf("%s: %llu bytes over %s at %u baud%s\n", name.c_str(), static_cast<unsigned long long>(r.bytes),
              o.link.c_str(), o.baud, r.simulated ? " (simulated time)" : "");
  std::printf("  time               %.3f s, goodput %.1f %% of %u bytes/s\n", r.seconds, r.goodput * 100, o.baud / 10);
  std::printf("  sessions           %u\n", r.sessions);
  std::printf("  frames             %u data, %u resent (%u lost on the line, %u received twice), %u probes "
              "after %u timeouts, %u waits for the client's line buffer, final payload %u B\n",
              r.host.data_frames_sent, r.host.retransmissions, r.host.losses, r.host.spurious, r.host.probes,
              r.host.timeouts, r.host.line_waits, r.final_frame_payload);
  if (r.simulated)
    std::printf("  client             %u chunks verified, %u frames dropped (bad CRC %u)\n", r.client_chunks,
                r.client.dropped(), r.client.bad_crc);
  if (r.frame_records != 0) std::printf("  frame records      %u\n", r.frame_records);
  // What the client displayed: one line per frame, then its statistics.
  for (const link::FrameRecord& f : r.frames)
    std::printf("  frame %5u crc %08x parse %u decode %u (entropy %u transform %u) display %u at %u ms%s%s\n", f.index,
                f.crc, f.parse_instructions, f.decode_instructions, f.entropy_instructions, f.transform_instructions,
                f.display_instructions, f.received_ms, f.late ? " late" : "", f.steered ? " steered" : "");
  if (r.have_stats)
    std::printf("  client stats       %u frames shown, %u late, %u stream bytes, workspace %u of %u B, stack %u B, "
                "link %u resent, %u dropped\n",
                r.stats.frames_shown, r.stats.late_frames, r.stats.stream_bytes, r.stats.workspace_high_water,
                r.stats.workspace_budget, r.stats.stack_high_water, r.stats.link_retransmissions, r.stats.link_dropped);
  if (r.receipt && r.receipt_prefix) {
    std::printf("  client report      workspace full after the first %llu of %llu bytes, CRC-32C %08x: matches; "
                "the host stopped the stream: %llu bytes of it acknowledged in all\n",
                static_cast<unsigned long long>(r.receipt_bytes), static_cast<unsigned long long>(r.bytes),
                r.receipt_crc, static_cast<unsigned long long>(r.bytes_acked));
  } else if (r.receipt) {
    std::printf("  client report      %llu bytes, CRC-32C %08x: matches\n",
                static_cast<unsigned long long>(r.receipt_bytes), r.receipt_crc);
  }
  if (r.receipt) {
    std::printf("  goodbye            %s\n", r.goodbye_acked  ? "acknowledged by the client"
                                          : !r.goodbye_sent ? "not sent"
                                          : r.client_closed ? "sent; then the client closed the line"
                                                            : "sent; not acknowledged within 10 s");
  }
}

void check_serve_report(const link::ServeReport& r) {
  if (r.receipt) return;
  if (r.report_seen && r.report_status == static_cast<int32_t>(Status::ok)) {
    char crc[16];
    std::snprintf(crc, sizeof crc, "%08x", r.receipt_crc);
    throw Failure(kExitBadInput, std::string("the client's report (") +
                                     (r.receipt_prefix ? "workspace full after " : "") +
                                     std::to_string(r.receipt_bytes) + " bytes, CRC-32C " + crc + ") does not match " +
                                     (r.receipt_prefix ? "that prefix of the stream" : "the stream"));
  } else if (r.report_seen) {
    throw Failure(kExitBadInput, "the client reports status " + std::to_string(r.report_status) + " (" +
                                     status_name(static_cast<Status>(r.report_status)) + ") after " +
                                     std::to_string(r.receipt_bytes) + " bytes: it did not play the whole stream");
  } else {
    std::printf("  client report      none (all bytes acknowledged; the client sent no report)\n");
  }
}

namespace {

void run_serve(const ServeArgs& a) {
  std::vector<uint8_t> bytes;
  try {
    bytes = enc::read_file(a.stream);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, e.what());
  }
  link::ServeOptions o;
  o.link = a.link;
  o.baud = a.baud;
  o.paced = !a.unpaced;
  o.timeout_s = a.timeout;
  o.faults.seed = a.seed;
  o.faults.bit_error_rate = a.ber;
  o.faults.frame_drop_rate = a.frame_loss;
  if (a.link != "loopback" && (a.ber != 0 || a.frame_loss != 0))
    throw Failure(kExitUsage, "--ber and --frame-loss simulate faults on --link loopback only");
  link::ServeReport r;
  try {
    r = link::serve_stream(bytes, o, [](const std::string& m) { std::fprintf(stderr, "vds serve: %s\n", m.c_str()); });
  } catch (const link::BackendError& e) {
    throw backend_failure(e);
  } catch (const std::runtime_error& e) {
    throw Failure(kExitBadInput, a.stream + ": " + e.what());
  }
  print_serve_report(a.stream, o, r);
  if (!a.crc_out.empty()) {
    std::string text;
    for (const link::FrameRecord& f : r.frames) {
      char line[16];
      std::snprintf(line, sizeof line, "%08x\n", f.crc);
      text += line;
    }
    enc::write_file(a.crc_out, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
  check_serve_report(r);
}

}  // namespace

void add_serve(CLI::App& app) {
  auto a = std::make_shared<ServeArgs>();
  CLI::App* sub = app.add_subcommand("serve", "Stream a file over a link to a client");
  sub->add_option("STREAM", a->stream, "Stream file (made with vds pack)")->required();
  sub->add_option("--link", a->link,
                  "loopback | pty:PATH | tcp:HOST:PORT | tcp-listen:PORT | usb:VID:PID[:IFACE[:EPIN:EPOUT]]")
      ->capture_default_str();
  sub->add_option("--baud", a->baud, "Line rate (serial and simulated links)")->capture_default_str()
      ->check(CLI::Range(1200u, 4000000u));
  sub->add_option("--timeout", a->timeout, "Give up after this many seconds (real links; 0: never)");
  sub->add_option("--ber", a->ber, "Loopback: bit-error rate")->check(CLI::Range(0.0, 0.01));
  sub->add_option("--frame-loss", a->frame_loss, "Loopback: fraction of frames lost")->check(CLI::Range(0.0, 0.5));
  sub->add_option("--crc-out", a->crc_out, "Write the CRC of every frame the client displayed, one hex line each");
  sub->add_option("--seed", a->seed, "Loopback: fault seed")->capture_default_str();
  sub->add_flag("--unpaced", a->unpaced,
                "pty and TCP: do not pace at --baud; write as fast as the client's line reports allow "
                "(measures how fast a client drains; goodput is still given against --baud)");
  sub->callback([a] { run_serve(*a); });
}

}  // namespace vds::cli
