"""Per-node network namespaces joined by veth pairs to a bridge, all created and removed
by the launcher.

Layout for a run with id R (short, so interface names fit in 15 bytes):

    netns kc-R-sw      holds bridge br0 and one veth end per node (v-<index>)
    netns kc-R-<i>     holds the node's end, eth0, with address 10.213.R.<i+1>/24

Nothing is created in the root namespace, so the host's interfaces, routes and firewall
are untouched; the addresses exist only inside these namespaces. `partition` takes a
node's link down on the bridge side; `heal` brings it back up.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass, field


class NetnsUnavailable(Exception):
    """This machine (or user) cannot create network namespaces."""


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=check)


def probe() -> str | None:
    """None when namespaces with veth work here; otherwise the reason they do not."""
    if shutil.which("ip") is None:
        return "the 'ip' command (iproute2) is not installed"
    if os.geteuid() != 0:
        return "network namespaces need root (run as root, or use the default loopback mode)"
    name = f"kc-probe-{os.getpid()}"
    try:
        _ip("netns", "add", name)
        _ip("-n", name, "link", "add", "pa", "type", "veth", "peer", "name", "pb")
    except subprocess.CalledProcessError as error:
        return f"cannot create a namespace with a veth pair: {error.stderr.strip()}"
    finally:
        _ip("netns", "del", name, check=False)
    return None


@dataclass
class Fabric:
    run_id: int
    nodes: list[str]
    created: list[str] = field(default_factory=list)

    @property
    def switch(self) -> str:
        return f"kc-{self.run_id}-sw"

    def namespace(self, node: str) -> str:
        return f"kc-{self.run_id}-{self.nodes.index(node)}"

    def address(self, node: str) -> str:
        return f"10.213.{self.run_id}.{self.nodes.index(node) + 1}"

    def peers(self) -> list[str]:
        return [self.address(n) for n in self.nodes]

    def create(self) -> None:
        _ip("netns", "add", self.switch)
        self.created.append(self.switch)
        _ip("-n", self.switch, "link", "add", "br0", "type", "bridge")
        _ip("-n", self.switch, "link", "set", "br0", "up")
        for index, node in enumerate(self.nodes):
            ns = self.namespace(node)
            _ip("netns", "add", ns)
            self.created.append(ns)
            _ip("-n", ns, "link", "set", "lo", "up")
            _ip("-n", self.switch, "link", "add", f"v-{index}", "type", "veth", "peer", "name", "eth0", "netns", ns)
            _ip("-n", self.switch, "link", "set", f"v-{index}", "master", "br0", "up")
            _ip("-n", ns, "addr", "add", f"{self.address(node)}/24", "dev", "eth0")
            _ip("-n", ns, "link", "set", "eth0", "up")

    def set_link(self, node: str, up: bool) -> None:
        index = self.nodes.index(node)
        _ip("-n", self.switch, "link", "set", f"v-{index}", "up" if up else "down")

    def command(self, node: str, argv: list[str]) -> list[str]:
        return ["ip", "netns", "exec", self.namespace(node), *argv]

    def destroy(self) -> None:
        for ns in reversed(self.created):
            _ip("netns", "del", ns, check=False)
        self.created.clear()
