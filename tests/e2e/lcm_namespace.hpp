// Helpers for end-to-end tests over UDP multicast: a private network namespace per test
// (it sends nothing anywhere but its own loopback), optionally with packet loss.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace rilbed::e2e {

// Runs `body` (shell lines, with $R the rilbed binary and $URL the bus) in a fresh network
// namespace whose loopback carries multicast; with `lossy`, one UDP packet to port 7667 in
// ten (and to 7668, where agent processes answer a run: agent_reply_url) is dropped at
// random on the input hook (nft counters: the first rule counts every
// packet, the second the dropped ones). Returns the exit status, or -1 when the script did
// not exit normally. The script has $XDG_RUNTIME_DIR in its folder (a run writes its token
// there) and `listening N`, which waits until N sockets are bound to LCM's port.
inline int in_namespace(const std::filesystem::path& dir, const std::string& body, bool lossy = false) {
  const std::filesystem::path script = dir / "ns.sh";
  std::ofstream out(script);
  out << "set -e\nip link set lo up\nip link set lo multicast on\nip route add 224.0.0.0/4 dev lo\n";
  if (lossy) {
    out << "nft add table inet loss\n"
           "nft add chain inet loss in '{ type filter hook input priority 0; policy accept; }'\n"
           "nft add rule inet loss in udp dport '{ 7667, 7668 }' counter\n"
           "nft add rule inet loss in udp dport '{ 7667, 7668 }' numgen random mod 10 0 counter drop\n";
  }
  out << "R='" << RILBED_BINARY << "'\nURL='udpm://239.255.76.67:7667?ttl=0'\ncd '" << dir.string() << "'\n"
      << "export XDG_RUNTIME_DIR=\"$PWD/xdg\"; mkdir -m 700 xdg\n"
      // Waits (polling) until N sockets are bound to LCM's port: listeners that have subscribed.
      << "listening() { for i in $(seq 1 400); do [ \"$(ss -lun 2>/dev/null | grep -c ':7667 ')\" -ge \"$1\" ] && "
         "return 0; "
         "sleep 0.05; done; echo \"fewer than $1 listeners\" >&2; return 1; }\n"
      << body;
  if (lossy) out << "\nnft list ruleset > nft.txt\n";
  out.close();
  const int status =
      std::system(("unshare -n /bin/bash '" + script.string() + "' >'" + (dir / "ns.log").string() + "' 2>&1").c_str());
  if (!WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

inline bool namespaces_work() { return std::system("unshare -n true >/dev/null 2>&1") == 0; }

// nft can add a table inside a namespace (the package is installed and the kernel has nf_tables).
inline bool nft_works() { return std::system("unshare -n nft add table inet probe >/dev/null 2>&1") == 0; }

#define SKIP_WITHOUT_NAMESPACES() \
  if (!namespaces_work()) GTEST_SKIP() << "cannot make a network namespace here (unshare -n needs root)"
#define SKIP_WITHOUT_NFT()   \
  SKIP_WITHOUT_NAMESPACES(); \
  if (!nft_works()) GTEST_SKIP() << "nft cannot add rules in a network namespace here (package nftables)"

}  // namespace rilbed::e2e
