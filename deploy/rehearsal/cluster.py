"""A campaign's Dask cluster rehearsed across hosts on this machine (docs/hosts.md): a scheduler
in one network namespace, a worker in each of the others, and ``deploy/run_campaign.py
--cluster`` flying the campaign on them from this namespace, through the rehearsal's switch.

    python -m deploy.rehearsal.cluster [--workers 2] [--link-delay-ms MS]
        [--tear-down-after N] -- --campaign deploy/campaigns/paper.toml --out runs/c [...]

Everything after ``--`` goes to ``run_campaign.py`` (which is given ``--cluster``).  With
``--tear-down-after N`` the first worker's host goes away once N runs have finished: its link
cut, its worker killed, its namespace removed, as a machine lost mid-campaign.  The scheduler
notices within ``WORKER_TTL`` and the runs it held go to the other workers.  The exit status is
the campaign's; every namespace, link and process is removed at the end.
"""

from __future__ import annotations

import argparse
import ipaddress
import logging
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from deploy.cluster import ClusterError, dask_client
from deploy.host_map import LinkSpec
from deploy.processes import Child, Supervisor, die_with_parent
from deploy.rehearsal import netns
from deploy.rehearsal.netns import RehearsalError
from deploy.rehearsal.network import RehearsedNetwork

REPO = Path(__file__).resolve().parents[2]
NETWORK = ipaddress.IPv4Network("10.79.0.0/24")
SCHEDULER_PORT = 8786
WORKER_TTL = "10s"
"""How long the scheduler waits on a silent worker before its runs go elsewhere (Dask's
default, 5 minutes, is for real clusters; a rehearsal's lost host should show within a run)."""
READY_S = 60.0
log = logging.getLogger("insp.cluster")


@dataclass(frozen=True)
class ClusterHost:
    """A host of the rehearsed cluster."""

    name: str
    address: ipaddress.IPv4Address
    link: LinkSpec = field(default_factory=LinkSpec)


def cluster_hosts(workers: int, link: LinkSpec) -> list[ClusterHost]:
    """The scheduler's host (``sched``) and ``workers`` worker hosts (``w1``...)."""
    first = NETWORK.network_address
    return [ClusterHost("sched", first + 1, link),
            *(ClusterHost(f"w{i}", first + 10 + i, link) for i in range(1, workers + 1))]


def scheduler_address(hosts: list[ClusterHost]) -> str:
    return f"tcp://{hosts[0].address}:{SCHEDULER_PORT}"


def start_cluster(sup: Supervisor, net: RehearsedNetwork, hosts: list[ClusterHost],
                  logs: Path) -> None:
    """The scheduler and one single-threaded worker per worker host, each in its namespace."""
    os.environ["DASK_DISTRIBUTED__SCHEDULER__WORKER_TTL"] = WORKER_TTL  # the children's
    sched = hosts[0]
    sup.start(Child("scheduler", ["-m", "distributed.cli.dask_scheduler", "--host",
                                  str(sched.address), "--port", str(SCHEDULER_PORT),
                                  "--no-dashboard"],
                    logs / "scheduler.log", net.netns(sched.name)))
    for h in hosts[1:]:
        sup.start(Child(f"worker-{h.name}", [
            "-m", "distributed.cli.dask_worker", scheduler_address(hosts), "--nworkers", "1",
            "--nthreads", "1", "--host", str(h.address), "--no-dashboard"],
            logs / f"worker-{h.name}.log", net.netns(h.name)))
    _wait_for_workers(scheduler_address(hosts), len(hosts) - 1)


def _wait_for_workers(address: str, n: int) -> None:
    """Until the scheduler at ``address`` has ``n`` workers (``READY_S`` at most)."""
    try:
        with dask_client(address, READY_S) as client:
            client.wait_for_workers(n, timeout=READY_S)
    except (ClusterError, TimeoutError) as e:
        raise RehearsalError(f"the rehearsed cluster did not come up: {e}") from None


def tear_down_host(sup: Supervisor, net: RehearsedNetwork, host: str) -> None:
    """``host`` goes away: its link cut, its processes killed, its namespace removed."""
    net.set_link(host, LinkSpec(), up=False)
    for child in sup.children:
        if child.netns == net.netns(host):
            child.signal(9)
            child.wait(10.0)
    netns.remove(net.netns(host))
    log.warning("host %s torn down (link cut, worker killed, namespace removed)", host)


def finished_runs(out: Path) -> int:
    """The campaign's finished runs so far (their summaries, out of partial folders)."""
    return sum(1 for p in (out / "runs").glob("*/summary.json") if "." not in p.parent.name)


def _out_of(campaign_args: list[str]) -> Path:
    try:
        return Path(campaign_args[campaign_args.index("--out") + 1])
    except (ValueError, IndexError):
        raise SystemExit("error: give run_campaign.py its --out after --") from None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ours, campaign_args = (argv[:argv.index("--")], argv[argv.index("--") + 1:]) \
        if "--" in argv else (argv, [])
    p = argparse.ArgumentParser(prog="python -m deploy.rehearsal.cluster", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--link-delay-ms", type=float, default=0.0)
    p.add_argument("--tear-down-after", type=int, metavar="N",
                   help="the first worker's host goes away once N runs have finished")
    args = p.parse_args(ours)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s cluster %(levelname)s %(message)s",
                        datefmt="%H:%M:%S")
    # SIGTERM ends it as Ctrl-C does: the campaign stopped, everything made removed
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    out = _out_of(campaign_args)
    logs = out / "cluster-logs"
    hosts = cluster_hosts(args.workers, LinkSpec(delay_ms=args.link_delay_ms))
    try:
        netns.require_privilege()
        with RehearsedNetwork(hosts, NETWORK, logs, seed=0) as net:
            sup = Supervisor(REPO)
            try:
                start_cluster(sup, net, hosts, logs)
                return _fly(sup, net, hosts, campaign_args, out, args.tear_down_after)
            finally:
                sup.stop_all()
    except RehearsalError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: the cluster's hosts removed", file=sys.stderr)
        return 130


def _fly(sup: Supervisor, net: RehearsedNetwork, hosts: list[ClusterHost],
         campaign_args: list[str], out: Path, tear_down_after: int | None) -> int:
    """Run the campaign on the cluster, tearing a worker's host down when due."""
    campaign = subprocess.Popen([sys.executable, str(REPO / "deploy" / "run_campaign.py"),
                                 *campaign_args, "--cluster", scheduler_address(hosts)],
                                cwd=REPO, env={**os.environ, "PYTHONUNBUFFERED": "1"},
                                preexec_fn=die_with_parent)
    try:
        while campaign.poll() is None:
            if tear_down_after is not None and finished_runs(out) >= tear_down_after:
                tear_down_host(sup, net, hosts[1].name)
                tear_down_after = None
            time.sleep(0.5)
    finally:
        if campaign.poll() is None:
            campaign.terminate()
            campaign.wait(30)
    return campaign.returncode


if __name__ == "__main__":
    raise SystemExit(main())
