// brdfa-server: parse flags, open the device, serve until SIGTERM/SIGINT, exit 0.
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include "app/http_server.h"
#include "brdfa/heap_tuning.h"
#include "config/config.h"

int main(int argc, char** argv) {
  brdfa::keepFrameBuffersInHeap();
  // A client that disconnects mid-write must cost an error return, not the process.
  ::signal(SIGPIPE, SIG_IGN);
  // Block the stop signals before any thread exists (the device driver starts some), so they
  // are only ever taken by the sigwait thread below, which can safely call stop().
  sigset_t stopSignals;
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

  brdfa::server::ParseOutcome parsed = brdfa::server::parse_command_line(argc, argv);
  if (!parsed.config) {
    std::fputs(parsed.message.c_str(), parsed.exitCode == 0 ? stdout : stderr);
    return parsed.exitCode;
  }
  const brdfa::server::ServerConfig& config = *parsed.config;

  std::vector<std::string> log;
  auto server = brdfa::server::HttpServer::create(config, log);
  for (const std::string& line : log) std::fprintf(stderr, "%s\n", line.c_str());
  if (!server) {
    std::fprintf(stderr, "brdfa-server: cannot start: %s\n", server.error().message.c_str());
    return 1;
  }
  brdfa::Result<int> port = server.value()->bind();
  if (!port) {
    std::fprintf(stderr, "brdfa-server: %s\n", port.error().message.c_str());
    return 1;
  }

  std::atomic<bool> serving{true};
  std::thread signalThread([&] {
    int sig = 0;
    sigwait(&stopSignals, &sig);
    if (serving && sig == SIGTERM && config.drainSeconds > 0) {
      // Drain: no new sessions or jobs; open streams and requests go on until they end or the
      // time is up. A second signal cuts it short.
      std::fprintf(stderr, "brdfa-server: SIGTERM, draining for up to %g s\n", config.drainSeconds);
      server.value()->beginDrain();
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(config.drainSeconds);
      while (serving && !server.value()->drained() && std::chrono::steady_clock::now() < deadline) {
        timespec slice{0, 100'000'000};
        if (sigtimedwait(&stopSignals, nullptr, &slice) > 0) {
          std::fprintf(stderr, "brdfa-server: second signal, not waiting for the drain\n");
          break;
        }
      }
    }
    if (serving) std::fprintf(stderr, "brdfa-server: signal %d, stopping\n", sig);
    // Repeated until run() returns: a signal that arrives before the listener has started
    // would otherwise be lost (httplib's stop() does nothing while it is not yet running).
    while (serving) {
      server.value()->stop();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });

  std::printf("listening on http://%s:%d\n", config.host.c_str(), port.value());
  std::fflush(stdout);
  bool ok = server.value()->run();
  serving = false;
  // run() also returns when the listener fails; wake the signal thread so it can be joined.
  pthread_kill(signalThread.native_handle(), SIGTERM);
  signalThread.join();
  server.value().reset();  // sessions stop and join, views and device are released
  std::fprintf(stderr, "brdfa-server: stopped\n");
  return ok ? 0 : 1;
}
