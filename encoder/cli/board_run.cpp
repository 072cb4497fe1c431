// Playing on a simulated client board (board_run.h).
#include "board_run.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "commands.h"
#include "serve_report.h"
#include "vds/enc/stream_writer.h"

extern char** environ;

namespace vds::cli {
namespace {

namespace fs = std::filesystem;

// A board process whose stdout and stderr go to a log file.
class BoardProcess {
 public:
  BoardProcess(const std::vector<std::string>& argv, const fs::path& log, bool search_path) : log_(log) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int e = search_path ? posix_spawnp(&pid_, args[0], &fa, nullptr, args.data(), environ)
                              : posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (e != 0) throw Failure(kExitBadInput, "cannot start " + argv[0] + ": " + std::strerror(e));
  }
  ~BoardProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  bool running() {
    if (pid_ <= 0) return false;
    int st = 0;
    if (waitpid(pid_, &st, WNOHANG) == pid_) {
      pid_ = 0;
      status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      return false;
    }
    return true;
  }
  // Waits up to `seconds` for the process to end; kills it after that.
  // Its exit status, or -1 if it had to be killed.
  int finish(double seconds) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (running() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!running()) return status_;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = 0;
    return -1;
  }
  std::string log() const {
    std::ifstream f(log_);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  }

 private:
  fs::path log_;
  pid_t pid_ = 0;
  int status_ = 0;
};

fs::path build_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::current_path() : exe.parent_path().parent_path();  // <build>/encoder/vds
}

uint16_t free_port() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (s < 0 || bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      getsockname(s, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    if (s >= 0) close(s);
    throw Failure(kExitInternal, "no free TCP port on 127.0.0.1");
  }
  close(s);
  return ntohs(a.sin_port);
}

}  // namespace

BoardResult run_on_board(const BoardArgs& a, const std::string& name, const ServeFn& serve) {
  const bool host = a.board == "host";
  fs::path firmware = a.firmware;
  if (firmware.empty())
    firmware = build_dir() / (host ? "firmware_sim/vds_fw_client_host" : "cm4/firmware_sim/vds_fw_client.elf");
  if (!fs::exists(firmware))
    throw Failure(kExitUsage, "the " + a.board + " board's firmware " + firmware.string() + " is not there (build it, or give --firmware)");
  fs::path dir = a.out;
  if (dir.empty()) dir = fs::temp_directory_path() / ("vds-play-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path log = dir / "board.log";

  link::ServeOptions o;
  o.baud = a.baud;
  o.paced = true;
  o.timeout_s = a.timeout;
  o.link.clear();  // the board's, once it is up
  std::vector<std::string> argv;
  if (host) {
    argv = {firmware.string(), "--uart", "pty-new", "--baud", std::to_string(a.baud)};
    if (!a.out.empty())
      argv.insert(argv.end(), {"--frames", (dir / "frames").string(), "--y4m", (dir / "frames.y4m").string(), "--contact-sheet",
                               (dir / "contact_sheet.png").string()});
    if (a.window) argv.insert(argv.end(), {"--window", "--hold"});
    if (!a.controls.empty()) argv.insert(argv.end(), {"--controls", fs::absolute(a.controls).string()});
  } else {
    if (!a.controls.empty()) throw Failure(kExitUsage, "--controls is for the host board (the qemu board has no controls)");
    const uint16_t port = free_port();
    o.link = "tcp:127.0.0.1:" + std::to_string(port);
    argv = {a.qemu, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none", "-serial",
            "tcp:127.0.0.1:" + std::to_string(port) + ",server=on,wait=on", "-semihosting-config", "enable=on,target=native",
            "-icount", "shift=0", "-kernel", firmware.string()};
  }
  BoardProcess board(argv, log, !host);
  const auto say = [](const std::string& m) { std::fprintf(stderr, "vds play: %s\n", m.c_str()); };
  if (host) {
    // The board names its pseudo-terminal first thing.
    for (int i = 0; o.link.empty(); ++i) {
      const std::string text = board.log();
      const size_t at = text.find("uart: ");
      if (at != std::string::npos && text.find('\n', at) != std::string::npos) {
        const size_t end = text.find_first_of(" \n", at + 6);
        o.link = "pty:" + text.substr(at + 6, end - at - 6);
      } else if (!board.running() || i > 500) {
        throw Failure(kExitInternal, "the host board did not name its pseudo-terminal:\n" + text);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
  }
  link::ServeReport r;
  for (int attempt = 0;; ++attempt) {
    try {
      r = serve(o, say);
      break;
    } catch (const link::BackendError& e) {
      // QEMU takes a moment to listen.
      if (host || e.kind() != link::BackendError::Kind::not_found || attempt > 100 || !board.running()) {
        std::fprintf(stderr, "%s", board.log().c_str());
        throw backend_failure(e);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "%s", board.log().c_str());
      throw Failure(kExitBadInput, name + ": " + e.what());
    }
  }
  BoardResult out;
  // With a viewer (a live window, a controls script) the board keeps a
  // model in view for them: until the window is closed or the script ends,
  // within --timeout.
  out.status = board.finish(a.has_viewer() ? std::max<double>(60, a.timeout) : 60);
  out.report = r;
  out.options = o;
  out.dir = dir;
  out.log = log;
  return out;
}

void check_board_frames(const BoardArgs& a, const std::string& name, const BoardResult& br, const std::vector<uint32_t>& want) {
  const link::ServeOptions& o = br.options;
  const link::ServeReport& r = br.report;
  const bool host = a.board == "host";
  const fs::path& dir = br.dir;
  const fs::path& log = br.log;
  const int board_status = br.status;
  print_serve_report(name, o, r);
  std::string crcs;
  size_t same = 0, steered = 0;
  // A frame drawn as the viewer turned the model is not the stream's alone:
  // not compared, where there is a viewer (the host board's window or
  // controls script), and only from the first such frame on (once turned,
  // every later frame is).
  const bool viewer = a.has_viewer();
  for (size_t i = 0; i < r.frames.size(); ++i) {
    char line[24];
    std::snprintf(line, sizeof line, "%08x%s\n", r.frames[i].crc, r.frames[i].steered ? " steered" : "");
    crcs += line;
    if (viewer && r.frames[i].steered && r.frames[i].index == i && (steered > 0 || same == i))
      ++steered;
    else if (steered == 0 && i < want.size() && r.frames[i].index == i && r.frames[i].crc == want[i])
      ++same;
  }
  enc::write_file((dir / "crcs.txt").string(), std::span(reinterpret_cast<const uint8_t*>(crcs.data()), crcs.size()));
  std::printf("  replay             %zu frames; the %s board showed %zu, %zu of them equal to the replay's", want.size(),
              a.board.c_str(), r.frames.size(), same);
  if (steered > 0) std::printf(", %zu drawn as the viewer turned the model (not compared)", steered);
  std::printf("\n");
  std::printf("  board              exit status %d; log %s%s\n", board_status, log.string().c_str(),
              a.out.empty() ? "" : (host ? "; frames, frames.y4m, contact_sheet.png and crcs.txt beside it" : "; crcs.txt beside it"));
  check_serve_report(r);
  // A client whose workspace holds only part of a model shows fewer frames;
  // every frame it shows must be the replay's.
  if (same + steered != r.frames.size() || (!r.receipt_prefix && r.frames.size() != want.size()))
    throw Failure(kExitBadInput, "the " + a.board + " board's frames differ from the replay");
  if (board_status != 0) throw Failure(kExitBadInput, "the " + a.board + " board exited with status " + std::to_string(board_status));
}

}  // namespace vds::cli
