"""DDS Security credentials for a mission: what Cyclone DDS's builtin plugins (auth, access
control, crypto) need so that only the mission's nodes join and a node speaks only for
itself.

    DIR/ca.pem, DIR/ca.key          one self-signed CA (EC prime256v1), identity and permissions CA
    DIR/crl.pem                     the CA's CRL (empty unless nodes were revoked)
    DIR/governance.xml, .p7s        the domain rule (signed by the CA, S/MIME, -text)
    DIR/nodes/NAME/cert.pem         identity "CN=NAME,OU=MISSION,O=Keel"
    DIR/nodes/NAME/key.pem          its key (0600, unencrypted PKCS#8)
    DIR/nodes/NAME/permissions.xml, .p7s    the node's grant (signed by the CA)
    DIR/tools/monitor/...           "CN=keel-monitor,OU=MISSION,O=Keel": subscribe only
    DIR/operator/cert.pem, key.pem  the ground's operator, "CN=keel-operator,OU=MISSION,O=Keel":
                                    signs ground commands (docs/operations.md); the key stays
                                    on the ground, nodes get the certificate
    DIR/operator/permissions.xml, .p7s   the ground commands (verbs) it may send (signed by the CA)
    DIR/mission/signing.key, .pub   the Ed25519 key the launcher signs mission images with
                                    (the ground's); nodes get the public key and fly only
                                    images signed with it (keel-node --public-key)
    DIR/dds-tool.xml                a CYCLONEDDS_URI file for DDS tools, as the monitor
    DIR/manifest.json               what was made, for whom, valid when

Everything is made with the openssl command-line tool. The CA's database (for `openssl
ca`: issuing, revoking, the CRL) is kept in DIR/.ca/. nodes/cluster/README.md
("Security") says what the profiles, roles and files mean.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from keel_cluster.launcher import LaunchError

# Cyclone DDS's port mapping allows domain ids up to 232; the governance and permissions
# cover 0..230 (the launcher's leased domains stay inside: common.DOMAIN_LAST).
DOMAIN_MIN, DOMAIN_MAX = 0, 230

TOPICS = [
    "KeelData", "KeelReliableData", "KeelRequest", "KeelResponse", "KeelCommand",
    "KeelAck", "KeelHeartbeat", "KeelError", "KeelLarge", "KeelNodeState",
    # Sampled data with a backup publisher (core/net/dds/sampled.hpp, the real-time switch).
    "KeelSampled",
]
# Only processing nodes command (master/observer roles live on them).
COMMAND_TOPICS = {"KeelCommand"}

PROFILES: dict[str, dict[str, str]] = {
    # Data encrypted, submessages signed: an outsider can neither read nor inject.
    "encrypt": {"rtps": "NONE", "metadata": "SIGN", "data": "ENCRYPT"},
    # Every RTPS message encrypted as well (hides even which entities talk).
    "full": {"rtps": "ENCRYPT", "metadata": "ENCRYPT", "data": "ENCRYPT"},
    # Authenticated and signed, nothing encrypted (readable on the wire, not forgeable).
    "sign": {"rtps": "NONE", "metadata": "SIGN", "data": "SIGN"},
}
DEFAULT_PROFILE = "encrypt"
DEFAULT_DAYS = 30
# ensure_credentials reuses a set only while it stays valid for at least this long.
MIN_REMAINING_S = 3600

# The protocol's topics whose samples are typed fields (core/net/dds/typed_wire.hpp).
TYPED_TOPICS = ("KeelHeartbeat", "KeelCommand", "KeelAck")
MONITOR = "monitor"
MONITOR_CN = "keel-monitor"
MISSION_KEY = "mission/signing.key"  # the set's mission-image signing key (the ground's)
OPERATOR = "operator"
OPERATOR_CN = "keel-operator"
# The ground commands a node takes (core/node/ground.hpp, kGroundVerbs).
GROUND_VERBS = ("phase", "recover", "exclude", "readmit", "pause-task", "resume-task", "designate")
MANIFEST = "manifest.json"
CA_DB = ".ca"
# Debian ships Cyclone's security plugins in a folder of its own, off the loader's path:
# dds-tool.xml names them by path when they are there.
PLUGIN_DIRS = [Path("/usr/lib/x86_64-linux-gnu/libddsc0debian"), Path("/usr/lib/aarch64-linux-gnu/libddsc0debian")]
PLUGINS = {"Authentication": "dds_security_auth", "AccessControl": "dds_security_ac",
           "Cryptographic": "dds_security_crypto"}
# The participants per host that can discover each other (core/net/dds: DdsConfig).
MAX_AUTO_PARTICIPANT_INDEX = 30

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,62}$")
# Characters a mission name may use in a certificate subject (no RFC 2253 escaping needed).
_MISSION = re.compile(r"^[A-Za-z0-9_.:()@-](?:[A-Za-z0-9 _.:()@-]{0,62}[A-Za-z0-9_.:()@-])?$")


class CredentialsError(LaunchError):
    """A one-line reason: the file it is about and what went wrong."""


@dataclass
class Manifest:
    directory: Path
    mission: str
    created_utc: str
    not_before: str
    not_after: str
    profile: str
    nodes: dict[str, dict[str, Any]]
    tools: dict[str, dict[str, Any]]
    revoked: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return {
            "mission": self.mission,
            "created_utc": self.created_utc,
            "not_before": self.not_before,
            "not_after": self.not_after,
            "profile": self.profile,
            "domains": [DOMAIN_MIN, DOMAIN_MAX],
            "nodes": self.nodes,
            "tools": self.tools,
            "revoked": self.revoked,
        }

    @property
    def expires(self) -> dt.datetime:
        return _parse_utc(self.not_after)

    @property
    def starts(self) -> dt.datetime:
        return _parse_utc(self.not_before)

    def save(self) -> None:
        _write(self.directory / MANIFEST, json.dumps(self.as_dict(), indent=2) + "\n")

    @classmethod
    def load(cls, directory: Path) -> Manifest:
        path = directory / MANIFEST
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
            return cls(directory, str(raw["mission"]), str(raw["created_utc"]), str(raw["not_before"]),
                       str(raw["not_after"]), str(raw["profile"]), dict(raw["nodes"]), dict(raw["tools"]),
                       list(raw.get("revoked") or []))
        except OSError as error:
            raise CredentialsError(f"{path}: cannot read: {error.strerror}") from None
        except (ValueError, KeyError, TypeError) as error:
            raise CredentialsError(f"{path}: not a credentials manifest ({error})") from None


@dataclass
class MissionNode:
    name: str
    address: int
    kind: str  # the mission's kind: processing or interface
    role: str | None  # an interface node's role (storage, interface), if any

    @property
    def commands(self) -> bool:
        return self.kind == "processing"


# -- the mission ---------------------------------------------------------------------------


def mission_nodes(mission_path: Path) -> tuple[str, list[MissionNode]]:
    """The mission's name and its nodes with their addresses: a node's address is its index
    in the mission's node list (core/mission: Mission::address_of; an image's node ids)."""
    from keel_cluster.common import read_mission

    path = Path(mission_path)
    if not path.is_file():
        raise CredentialsError(f"{path}: cannot read the mission: no such file")
    try:
        raw = read_mission(path)
    except LaunchError as error:
        raise CredentialsError(str(error).splitlines()[0]) from None
    except OSError as error:
        raise CredentialsError(f"{path}: cannot read the mission: {error.strerror}") from None
    except Exception as error:  # noqa: BLE001 - yaml's errors, bad encodings
        first = str(error).strip().splitlines()
        raise CredentialsError(f"{path}: not a mission ({type(error).__name__}: {first[0] if first else ''})") from None
    if not isinstance(raw, dict) or not isinstance(raw.get("nodes"), dict) or not raw["nodes"]:
        raise CredentialsError(f"{path}: not a mission (no `nodes`)")
    name = raw.get("mission")
    if not isinstance(name, str) or not _MISSION.match(name):
        raise CredentialsError(
            f"{path}: mission name {name!r} cannot go into a certificate subject "
            "(letters, digits, space and _.:()@- only); run with --insecure")
    nodes: list[MissionNode] = []
    for address, (node, spec) in enumerate(raw["nodes"].items()):
        node = str(node)
        if not _NAME.match(node):
            raise CredentialsError(f"{path}: node name {node!r} is not a plain name")
        spec = spec if isinstance(spec, dict) else {}
        kind = str(spec.get("kind", ""))
        if kind not in ("processing", "interface"):
            raise CredentialsError(f"{path}: node {node}: kind {kind!r} is neither processing nor interface")
        role = spec.get("role")
        nodes.append(MissionNode(node, address, kind, str(role) if role is not None else None))
    return name, nodes


def subject(name: str, mission: str) -> str:
    """The certificate subject in RFC 2253 form, as Cyclone compares it with the
    permissions' subject_name."""
    return f"CN={name},OU={mission},O=Keel"


def _subj_arg(name: str, mission: str) -> str:
    return f"/O=Keel/OU={mission}/CN={name}"


# -- openssl ----------------------------------------------------------------------------------


def _openssl(args: list[str], *, about: Path | str, cwd: Path | None = None, stdin: str | None = None) -> str:
    command = ["openssl", *args]
    try:
        done = subprocess.run(command, capture_output=True, text=True, cwd=cwd, input=stdin,
                              timeout=60, check=False, umask=0o077)
    except FileNotFoundError:
        raise CredentialsError(f"{about}: the openssl command is not installed (apt install openssl)") from None
    except subprocess.TimeoutExpired:
        raise CredentialsError(f"{about}: openssl {args[0]} gave no answer in 60 s") from None
    except OSError as error:
        raise CredentialsError(f"{about}: cannot run openssl: {error}") from None
    if done.returncode != 0:
        lines = [line.strip() for line in done.stderr.splitlines() if line.strip()]
        # openssl's last lines are the error queue; the first is usually the reason.
        reason = next((line for line in lines if "error" in line.lower() or ":" in line), lines[0] if lines else "")
        raise CredentialsError(f"{about}: openssl {args[0]} failed (exit {done.returncode}): {reason[:300]}")
    return done.stdout


def _asn1(moment: dt.datetime) -> str:
    """openssl ca's -startdate/-enddate (UTCTime up to 2049, then GeneralizedTime)."""
    return moment.strftime("%y%m%d%H%M%SZ" if moment.year < 2050 else "%Y%m%d%H%M%SZ")


def _xml_time(moment: dt.datetime) -> str:
    return moment.strftime("%Y-%m-%dT%H:%M:%S")


def _iso(moment: dt.datetime) -> str:
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")


def _parse_utc(text: str) -> dt.datetime:
    return dt.datetime.strptime(text.rstrip("Z"), "%Y-%m-%dT%H:%M:%S").replace(tzinfo=dt.UTC)


def _now() -> dt.datetime:
    return dt.datetime.now(dt.UTC).replace(microsecond=0)


def _write(path: Path, text: str, mode: int = 0o644) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    os.chmod(path, mode)


def _ca_config(directory: Path) -> Path:
    """The openssl ca configuration for the CA database in directory/.ca (written before
    each use: the directory may have been moved since)."""
    db = directory / CA_DB
    (db / "issued").mkdir(parents=True, exist_ok=True)
    for name, initial in (("index.txt", ""), ("serial", "1000\n"), ("crlnumber", "1000\n")):
        if not (db / name).exists():
            _write(db / name, initial, 0o600)
    text = f"""# openssl ca's database for this credentials set (keel_cluster.security)
[ ca ]
default_ca = keel_ca

[ keel_ca ]
dir = {db}
database = $dir/index.txt
serial = $dir/serial
crlnumber = $dir/crlnumber
new_certs_dir = $dir/issued
certificate = {directory / "ca.pem"}
private_key = {directory / "ca.key"}
default_md = sha256
default_crl_days = {DEFAULT_DAYS}
policy = keel_policy
unique_subject = no
copy_extensions = none
email_in_dn = no
preserve = yes

[ keel_policy ]
organizationName = supplied
organizationalUnitName = supplied
commonName = supplied

[ req ]
distinguished_name = req_dn
prompt = no

[ req_dn ]
O = Keel

[ ca_ext ]
basicConstraints = critical, CA:TRUE
keyUsage = critical, keyCertSign, cRLSign, digitalSignature
subjectKeyIdentifier = hash

[ identity_ext ]
basicConstraints = critical, CA:FALSE
keyUsage = critical, digitalSignature, keyAgreement
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
"""
    config = db / "openssl.cnf"
    _write(config, text, 0o600)
    return config


def _new_signing_key(key: Path) -> None:
    """An Ed25519 key for mission images (keel-verify compile --sign-key) and its public
    key beside it (.pub, PEM: keel-node --public-key)."""
    key.parent.mkdir(parents=True, exist_ok=True)
    _openssl(["genpkey", "-algorithm", "ed25519", "-out", str(key)], about=key)
    os.chmod(key, 0o600)
    _openssl(["pkey", "-in", str(key), "-pubout", "-out", str(key.with_suffix(".pub"))], about=key)
    os.chmod(key.with_suffix(".pub"), 0o644)


def _new_key(path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    _openssl(["genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1",
              "-pkeyopt", "ec_param_enc:named_curve", "-out", str(path)], about=path)
    os.chmod(path, 0o600)


def _issue(directory: Path, config: Path, key: Path, cert: Path, subj: str, start: dt.datetime,
           end: dt.datetime, *, self_sign: bool = False) -> None:
    csr = cert.with_suffix(".csr")
    _openssl(["req", "-new", "-config", str(config), "-key", str(key), "-subj", subj, "-out", str(csr)],
             about=csr)
    args = ["ca", "-batch", "-config", str(config), "-in", str(csr), "-out", str(cert), "-notext",
            "-preserveDN", "-startdate", _asn1(start), "-enddate", _asn1(end),
            "-extensions", "ca_ext" if self_sign else "identity_ext"]
    if self_sign:
        args += ["-selfsign", "-keyfile", str(key)]
    _openssl(args, about=cert)
    csr.unlink()
    os.chmod(cert, 0o644)


def _gen_crl(directory: Path, config: Path, until: dt.datetime) -> None:
    # The CRL must not expire before the certificates do: OpenSSL (and so Cyclone) refuses
    # every peer once the CRL's nextUpdate has passed.
    hours = max(1, int((until - _now()).total_seconds() // 3600) + 24)
    crl = directory / "crl.pem"
    _openssl(["ca", "-batch", "-config", str(config), "-gencrl", "-crlhours", str(hours), "-out", str(crl)],
             about=crl)
    os.chmod(crl, 0o644)


def _sign(directory: Path, document: Path) -> Path:
    signed = document.with_suffix(".p7s")
    _openssl(["smime", "-sign", "-text", "-in", str(document), "-out", str(signed),
              "-signer", str(directory / "ca.pem"), "-inkey", str(directory / "ca.key")], about=signed)
    os.chmod(signed, 0o644)
    return signed


# -- documents ------------------------------------------------------------------------------


def governance_xml(profile: str) -> str:
    kinds = PROFILES[profile]
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- Keel governance, profile "{profile}": rtps_protection_kind {kinds["rtps"]},
     metadata_protection_kind {kinds["metadata"]}, data_protection_kind {kinds["data"]}.
     Written by keel-cluster credentials (keel_cluster/security.py); signed by the mission's CA in governance.p7s. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range><min>{DOMAIN_MIN}</min><max>{DOMAIN_MAX}</max></id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>{kinds["rtps"]}</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>{kinds["metadata"]}</metadata_protection_kind>
          <data_protection_kind>{kinds["data"]}</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
"""


def _rule(kind: str, topics: list[str], partitions: list[str]) -> str:
    topic_lines = "".join(f"            <topic>{t}</topic>\n" for t in topics)
    partition_lines = "".join(f"            <partition>{p}</partition>\n" for p in partitions)
    return (f"        <{kind}>\n          <topics>\n{topic_lines}          </topics>\n"
            f"          <partitions>\n{partition_lines}          </partitions>\n        </{kind}>\n")


def node_rules(node: MissionNode) -> tuple[list[str], list[str], list[str], list[str]]:
    """(publish topics, publish partitions, subscribe topics, subscribe partitions) of a node:
    its writers are in `keel.from.A` and, for addressed samples, `keel.node.D` or
    `keel.broadcast`; its readers in `keel.from.*` and its own `keel.node.A` and
    `keel.broadcast`."""
    publish = [t for t in TOPICS if node.commands or t not in COMMAND_TOPICS]
    return (publish, [f"keel.from.{node.address}", "keel.node.*", "keel.broadcast"],
            list(TOPICS), ["keel.from.*", f"keel.node.{node.address}", "keel.broadcast"])


def permissions_xml(grant: str, subj: str, start: dt.datetime, end: dt.datetime, rules: str, comment: str) -> str:
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- {comment} -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="{grant}">
      <subject_name>{subj}</subject_name>
      <validity>
        <not_before>{_xml_time(start)}</not_before>
        <not_after>{_xml_time(end)}</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range><min>{DOMAIN_MIN}</min><max>{DOMAIN_MAX}</max></id_range>
        </domains>
{rules}      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"""


def _uri(path: Path) -> str:
    return f"file:{path.resolve()}"


def security_section(directory: Path, identity: Path, permissions: Path | None = None) -> str:
    """The <Security> element of a Cyclone DDS configuration for the identity in the folder
    `identity` of the credentials `directory` (its permissions.p7s unless `permissions`
    names another signed document), plugins where Debian puts them."""

    def library(kind: str) -> str:
        for folder in PLUGIN_DIRS:
            candidate = folder / f"lib{PLUGINS[kind]}.so"
            if candidate.is_file():
                return f'        <Library path="{candidate}"/>\n'
        return ""

    return f"""    <Security>
      <Authentication>
{library("Authentication")}        <IdentityCertificate>{_uri(identity / "cert.pem")}</IdentityCertificate>
        <IdentityCA>{_uri(directory / "ca.pem")}</IdentityCA>
        <PrivateKey>{_uri(identity / "key.pem")}</PrivateKey>
        <CRL>{_uri(directory / "crl.pem")}</CRL>
      </Authentication>
      <AccessControl>
{library("AccessControl")}        <Governance>{_uri(directory / "governance.p7s")}</Governance>
        <PermissionsCA>{_uri(directory / "ca.pem")}</PermissionsCA>
        <Permissions>{_uri(permissions or identity / "permissions.p7s")}</Permissions>
      </AccessControl>
      <Cryptographic>
{library("Cryptographic")}      </Cryptographic>
    </Security>
"""


def dds_tool_xml(directory: Path) -> str:
    """A CYCLONEDDS_URI file for DDS tools joining a secured loopback cluster as the
    monitor (paths absolute: the file can be used from anywhere)."""
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- For DDS tools (cyclonedds, ddsperf) watching a secured Keel cluster on loopback, as
     "{MONITOR_CN}" (subscribes to every Keel topic, publishes nothing):
       CYCLONEDDS_URI=file://{directory.resolve() / "dds-tool.xml"} cyclonedds ps -i DOMAIN
     (KeelNodeState, KeelHeartbeat, KeelCommand and KeelAck are also written in the default
     partition; every other Keel topic only in partitions keel.from.N: a reader receives
     those only in a matching partition, keel.from.* or *.)
     Written by keel-cluster credentials. -->
<CycloneDDS>
  <Domain Id="any">
    <General>
      <Interfaces><NetworkInterface name="lo"/></Interfaces>
      <AllowMulticast>false</AllowMulticast>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>{MAX_AUTO_PARTICIPANT_INDEX}</MaxAutoParticipantIndex>
      <Peers><Peer address="127.0.0.1"/></Peers>
    </Discovery>
{security_section(directory, directory / "tools" / MONITOR)}  </Domain>
</CycloneDDS>
"""


# -- making, reusing, revoking ---------------------------------------------------------------


def operator_permissions_xml(subj: str, verbs: tuple[str, ...] | list[str], start: dt.datetime,
                             end: dt.datetime) -> str:
    """The operator's grant: the ground commands it may send, until when (core/net/dds/
    credentials.hpp, OperatorIdentity)."""
    return (f"<keel_operator_permissions>\n<subject_name>{subj}</subject_name>\n"
            f"<verbs>{' '.join(verbs)}</verbs>\n<not_before>{_xml_time(start)}</not_before>\n"
            f"<not_after>{_xml_time(end)}</not_after>\n</keel_operator_permissions>\n")


def _issue_node(directory: Path, config: Path, node: MissionNode, mission: str, start: dt.datetime,
                end: dt.datetime) -> str:
    """A new key, certificate and signed grant for `node` in directory/nodes/NAME; returns
    its subject."""
    folder = directory / "nodes" / node.name
    subj = subject(node.name, mission)
    _new_key(folder / "key.pem")
    _issue(directory, config, folder / "key.pem", folder / "cert.pem", _subj_arg(node.name, mission), start, end)
    pub_topics, pub_parts, sub_topics, sub_parts = node_rules(node)
    # The node's state and the protocol's typed topics it writes are also published in the
    # default partition, for DDS tools (core/net/README.md): a rule of their own, so no
    # other topic gains it.
    for_tools = ["KeelNodeState"] + [t for t in TYPED_TOPICS if t in pub_topics]
    rules = (_rule("publish", pub_topics, pub_parts)
             + _rule("publish", for_tools, [f"keel.from.{node.address}", ""])
             + _rule("subscribe", sub_topics, sub_parts))
    what = f"{node.kind}{' (' + node.role + ')' if node.role else ''} node {node.name}, address {node.address}"
    _write(folder / "permissions.xml",
           permissions_xml(node.name, subj, start, end, rules, f"Keel permissions of the {what}"))
    _sign(directory, folder / "permissions.xml")
    return subj


def make_credentials(mission_path: Path | str, out_dir: Path | str, *, days: int = DEFAULT_DAYS,
                     profile: str = DEFAULT_PROFILE, not_before: dt.datetime | None = None,
                     operator_verbs: tuple[str, ...] | list[str] = GROUND_VERBS) -> Manifest:
    """A new CA and credentials for every node of the mission and the monitor tool, in
    out_dir (replaced as a whole once the new set is complete)."""
    mission_path = Path(mission_path)
    out_dir = Path(out_dir).resolve()
    if profile not in PROFILES:
        raise CredentialsError(f"{out_dir}: unknown profile {profile!r} (known: {', '.join(PROFILES)})")
    if not isinstance(days, int) or days < 1:
        raise CredentialsError(f"{out_dir}: --days must be a whole number of days, at least 1 (got {days!r})")
    mission, nodes = mission_nodes(mission_path)
    unknown = [verb for verb in operator_verbs if verb not in GROUND_VERBS]
    if unknown or not operator_verbs:
        raise CredentialsError(f"{out_dir}: --operator-verbs: " +
                               (f"unknown ground command {unknown[0]!r}" if unknown else "none given") +
                               f" (known: {', '.join(GROUND_VERBS)})")
    if shutil.which("openssl") is None:
        raise CredentialsError(f"{out_dir}: the openssl command is not installed (apt install openssl)")
    start = (not_before or _now() - dt.timedelta(minutes=1)).astimezone(dt.UTC).replace(microsecond=0)
    end = start + dt.timedelta(days=days)
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.new-", dir=out_dir.parent))
    except OSError as error:
        raise CredentialsError(f"{out_dir}: cannot create: {error.strerror}") from None
    try:
        os.chmod(work, 0o700)
        # The CA's database names paths: generate in `work` with the final paths in the
        # documents, then move `work` into place.
        config = _ca_config(work)
        _new_key(work / "ca.key")
        _issue(work, config, work / "ca.key", work / "ca.pem", _subj_arg(f"Keel {mission} CA", mission),
               start, end, self_sign=True)
        _gen_crl(work, config, end)
        _write(work / "governance.xml", governance_xml(profile))
        _sign(work, work / "governance.xml")
        node_entries: dict[str, dict[str, Any]] = {}
        for node in nodes:
            subj = _issue_node(work, config, node, mission, start, end)
            node_entries[node.name] = {"address": node.address, "kind": node.kind, "role": node.role,
                                       "subject": subj, "commands": node.commands}
        monitor = work / "tools" / MONITOR
        monitor_subject = subject(MONITOR_CN, mission)
        _new_key(monitor / "key.pem")
        _issue(work, config, monitor / "key.pem", monitor / "cert.pem", _subj_arg(MONITOR_CN, mission), start, end)
        _write(monitor / "permissions.xml",
               permissions_xml(MONITOR_CN, monitor_subject, start, end, _rule("subscribe", list(TOPICS), ["*"]),
                               "Keel permissions of the monitor tool: subscribes to every Keel topic, "
                               "publishes nothing"))
        _sign(work, monitor / "permissions.xml")
        operator = work / OPERATOR
        operator_subject = subject(OPERATOR_CN, mission)
        _new_key(operator / "key.pem")
        _issue(work, config, operator / "key.pem", operator / "cert.pem", _subj_arg(OPERATOR_CN, mission), start, end)
        _write(operator / "permissions.xml", operator_permissions_xml(operator_subject, operator_verbs, start, end))
        _sign(work, operator / "permissions.xml")
        _new_signing_key(work / MISSION_KEY)
        _write(work / "dds-tool.xml", dds_tool_xml(out_dir))
        manifest = Manifest(out_dir, mission, _iso(_now()), _iso(start), _iso(end), profile, node_entries,
                            {MONITOR: {"subject": monitor_subject, "dir": f"tools/{MONITOR}",
                                       "publishes": False},
                             OPERATOR: {"subject": operator_subject, "dir": OPERATOR, "publishes": False,
                                        "verbs": list(operator_verbs)}})
        manifest.directory = work
        manifest.save()
        _replace(work, out_dir)
        manifest.directory = out_dir
        _ca_config(out_dir)  # the database's paths, now that it is in place
        return manifest
    except CredentialsError as error:
        shutil.rmtree(work, ignore_errors=True)
        # Name the folder the caller asked for, not the one the set was made in.
        raise CredentialsError(str(error).replace(str(work), str(out_dir))) from None
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise


def _replace(new: Path, out_dir: Path) -> None:
    old: Path | None = None
    try:
        if out_dir.exists():
            if not out_dir.is_dir():
                raise CredentialsError(f"{out_dir}: exists and is not a folder")
            if any(out_dir.iterdir()) and not (out_dir / MANIFEST).exists():
                raise CredentialsError(f"{out_dir}: a folder that is not a credentials set; choose another --out")
            old = out_dir.with_name(f".{out_dir.name}.old-{os.getpid()}")
            shutil.rmtree(old, ignore_errors=True)
            out_dir.rename(old)
        new.rename(out_dir)
        os.chmod(out_dir, 0o700)
    except OSError as error:
        raise CredentialsError(f"{out_dir}: cannot put the new credentials in place: {error.strerror}") from None
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _cert_dates(cert: Path) -> tuple[dt.datetime, dt.datetime, str]:
    out = _openssl(["x509", "-in", str(cert), "-noout", "-startdate", "-enddate", "-subject",
                    "-nameopt", "RFC2253"], about=cert)
    values = dict(line.split("=", 1) for line in out.splitlines() if "=" in line)

    def parse(text: str) -> dt.datetime:
        return dt.datetime.strptime(text.replace("  ", " ").strip(), "%b %d %H:%M:%S %Y GMT").replace(
            tzinfo=dt.UTC)

    return parse(values["notBefore"]), parse(values["notAfter"]), values.get("subject", "").strip()


def check_credentials(out_dir: Path | str, *, at: dt.datetime | None = None,
                      min_remaining_s: float = 0) -> list[str]:
    """Why the set in out_dir is not usable at `at` (default now) for at least
    min_remaining_s more seconds: one line per problem, none when it is. Checks the files,
    the key modes, every certificate against the CA (and its CRL's signature) and their
    validity."""
    out_dir = Path(out_dir)
    at = at or _now()
    try:
        manifest = Manifest.load(out_dir)
    except CredentialsError as error:
        return [str(error)]
    problems: list[str] = []
    identities = ([out_dir / "nodes" / n for n in manifest.nodes]
                  + [out_dir / "tools" / t for t in manifest.tools if t != OPERATOR] + [out_dir / OPERATOR])
    needed = [out_dir / n for n in ("ca.pem", "ca.key", "crl.pem", "governance.xml", "governance.p7s",
                                    "dds-tool.xml")]
    needed += [folder / f for folder in identities for f in ("cert.pem", "key.pem", "permissions.xml",
                                                             "permissions.p7s")]
    needed += [out_dir / MISSION_KEY, (out_dir / MISSION_KEY).with_suffix(".pub")]
    missing = [str(p) for p in needed if not p.is_file()]
    if missing:
        return [f"{m}: missing" for m in missing]
    for key in [out_dir / "ca.key", out_dir / MISSION_KEY, *(folder / "key.pem" for folder in identities)]:
        if key.stat().st_mode & 0o077:
            problems.append(f"{key}: readable by others (mode {key.stat().st_mode & 0o777:o}, should be 600)")
    try:
        _openssl(["verify", "-CAfile", str(out_dir / "ca.pem"), *(str(f / "cert.pem") for f in identities)],
                 about=out_dir / "ca.pem")
        _openssl(["crl", "-in", str(out_dir / "crl.pem"), "-noout", "-CAfile", str(out_dir / "ca.pem")],
                 about=out_dir / "crl.pem")
        for cert in [out_dir / "ca.pem", *(folder / "cert.pem" for folder in identities)]:
            start, end, _ = _cert_dates(cert)
            if start > at:
                problems.append(f"{cert}: not valid before {_iso(start)}")
            elif (end - at).total_seconds() < min_remaining_s:
                problems.append(f"{cert}: expires {_iso(end)}" + (" (expired)" if end <= at else ""))
    except CredentialsError as error:
        problems.append(str(error))
    return problems


def ensure_credentials(mission_path: Path | str, out_dir: Path | str, *, days: int = DEFAULT_DAYS,
                       profile: str = DEFAULT_PROFILE, min_remaining_s: float = MIN_REMAINING_S) -> Manifest:
    """The credentials in out_dir when they are for this mission's node set (names,
    addresses, kinds) and profile and stay valid for min_remaining_s more; else a new set."""
    out_dir = Path(out_dir).resolve()
    mission, nodes = mission_nodes(Path(mission_path))
    try:
        manifest = Manifest.load(out_dir)
    except CredentialsError:
        manifest = None
    if manifest is not None and reusable(manifest, mission, nodes, profile, min_remaining_s):
        return manifest
    return make_credentials(mission_path, out_dir, days=days, profile=profile)


def reusable(manifest: Manifest, mission: str, nodes: list[MissionNode], profile: str,
             min_remaining_s: float = MIN_REMAINING_S) -> bool:
    wanted = {n.name: (n.address, n.kind, subject(n.name, mission)) for n in nodes}
    have = {name: (e.get("address"), e.get("kind"), e.get("subject")) for name, e in manifest.nodes.items()}
    if manifest.mission != mission or manifest.profile != profile or wanted != have:
        return False
    if MONITOR not in manifest.tools or OPERATOR not in manifest.tools:
        return False
    return not check_credentials(manifest.directory, min_remaining_s=min_remaining_s)


def revoke(out_dir: Path | str, name: str) -> Manifest:
    """Adds the certificate of node (or tool) `name` to crl.pem, signed again by the CA.
    Every node must be given the new crl.pem."""
    out_dir = Path(out_dir).resolve()
    manifest = Manifest.load(out_dir)
    if name in manifest.nodes:
        cert = out_dir / "nodes" / name / "cert.pem"
    elif name in (OPERATOR, OPERATOR_CN):
        cert = out_dir / OPERATOR / "cert.pem"
    elif name in manifest.tools or name == MONITOR_CN:
        cert = out_dir / "tools" / MONITOR / "cert.pem"
        name = MONITOR
    else:
        known = ", ".join([*manifest.nodes, *manifest.tools])
        raise CredentialsError(f"{out_dir / MANIFEST}: no node or tool {name!r} (known: {known})")
    if not (out_dir / "ca.key").is_file():
        raise CredentialsError(f"{out_dir / 'ca.key'}: missing; only the CA's key can revoke")
    config = _ca_config(out_dir)
    if name not in manifest.revoked:
        _openssl(["ca", "-batch", "-config", str(config), "-revoke", str(cert), "-crl_reason", "keyCompromise"],
                 about=cert)
        manifest.revoked.append(name)
    _gen_crl(out_dir, config, manifest.expires)
    manifest.save()
    return manifest


_operator_keys: dict[Path, tuple[int, Any]] = {}  # key file -> (mtime, loaded key)


def ground_line(directory: Path | str, image_sha256: str, seq: int, verb: str, *arguments: str) -> str:
    """The control line that carries a ground command signed by the operator of the
    credentials in `directory` (core/node/ground.hpp): `ground SIGNATURE COMMAND`, COMMAND
    `keel-ground/1 image=IMAGE seq=SEQ VERB ARG...`, IMAGE the first 16 hex digits of the
    image's SHA-256, SIGNATURE the operator's ECDSA (SHA-256) signature of COMMAND in hex."""
    if verb not in GROUND_VERBS:
        raise CredentialsError(f"{verb!r}: not a ground command (known: {', '.join(GROUND_VERBS)})")
    key = Path(directory) / OPERATOR / "key.pem"
    if not key.is_file():
        raise CredentialsError(f"{key}: missing: the operator's key signs ground commands "
                               "(keel-cluster credentials makes it)")
    text = " ".join(["keel-ground/1", f"image={image_sha256[:16]}", f"seq={seq}", verb, *arguments])
    # Signed in this process (cryptography, as keel-verify signs images): an openssl
    # process per command took 5-10 ms, which a phase change waited for.
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec

    cached = _operator_keys.get(key)
    if cached is None or cached[0] != key.stat().st_mtime_ns:
        try:
            loaded = serialization.load_pem_private_key(key.read_bytes(), password=None)
        except (OSError, ValueError, TypeError) as error:
            raise CredentialsError(f"{key}: cannot use the operator's key: {error}") from None
        if not isinstance(loaded, ec.EllipticCurvePrivateKey):
            raise CredentialsError(f"{key}: not an EC key (the operator signs with ECDSA P-256)")
        cached = (key.stat().st_mtime_ns, loaded)
        _operator_keys[key] = cached
    signature = cached[1].sign(text.encode(), ec.ECDSA(hashes.SHA256()))
    return f"ground {signature.hex()} {text}"


def renew(out_dir: Path | str, name: str, *, days: int = DEFAULT_DAYS) -> Manifest:
    """Issues node (or the operator) `name` a new key, certificate and grant, valid from now
    for `days` (never past the CA's own expiry), signed by the set's CA; the old
    certificate stays valid until it expires (revoke it if it was compromised). The node
    takes them when it restarts; its peers accept them at once (the same CA). Needs the CA's
    key: done on the ground (docs/security.md, "Credentials: expiry, renewal and
    revocation")."""
    out_dir = Path(out_dir).resolve()
    manifest = Manifest.load(out_dir)
    if not isinstance(days, int) or days < 1:
        raise CredentialsError(f"{out_dir}: --days must be a whole number of days, at least 1 (got {days!r})")
    if not (out_dir / "ca.key").is_file():
        raise CredentialsError(f"{out_dir / 'ca.key'}: missing; only the CA's key can issue")
    start = (_now() - dt.timedelta(minutes=1)).replace(microsecond=0)
    _, ca_end, _ = _cert_dates(out_dir / "ca.pem")
    end = min(start + dt.timedelta(days=days), ca_end)
    if end <= _now():
        raise CredentialsError(f"{out_dir / 'ca.pem'}: the CA expired on {_iso(ca_end)}: make a new set")
    config = _ca_config(out_dir)
    if name in manifest.nodes:
        entry = manifest.nodes[name]
        node = MissionNode(name, int(entry["address"]), str(entry["kind"]), entry.get("role"))
        _issue_node(out_dir, config, node, manifest.mission, start, end)
        entry["not_after"] = _iso(end)
    elif name in (OPERATOR, OPERATOR_CN):
        folder = out_dir / OPERATOR
        entry = manifest.tools[OPERATOR]
        _new_key(folder / "key.pem")
        _issue(out_dir, config, folder / "key.pem", folder / "cert.pem", _subj_arg(OPERATOR_CN, manifest.mission),
               start, end)
        _write(folder / "permissions.xml",
               operator_permissions_xml(str(entry["subject"]), list(entry.get("verbs") or GROUND_VERBS), start, end))
        _sign(out_dir, folder / "permissions.xml")
        entry["not_after"] = _iso(end)
    else:
        known = ", ".join([*manifest.nodes, OPERATOR])
        raise CredentialsError(f"{out_dir / MANIFEST}: no node or operator {name!r} to renew (known: {known})")
    manifest.save()
    return manifest


KITS = "kits"
# What a node is given, relative to the set's folder: public material and its own key.
KIT_FILES = ("ca.pem", "crl.pem", "governance.p7s", "operator/cert.pem", "operator/permissions.p7s",
             "mission/signing.pub")


def node_kit(out_dir: Path | str, name: str) -> Path:
    """The folder node `name` is given as its --security DIR: the CA's certificate, the CRL,
    the governance, the operator's certificate and grant, and nodes/NAME/ (its certificate,
    key and grant). Never the CA's key, the operator's key or another node's key: keel-node
    refuses a folder that holds one. Made again at each call (DIR/kits/NAME), so a renewal
    or a new CRL reaches the node when it next starts."""
    out_dir = Path(out_dir).resolve()
    manifest = Manifest.load(out_dir)
    if name not in manifest.nodes:
        raise CredentialsError(f"{out_dir / MANIFEST}: no node {name!r} (known: {', '.join(manifest.nodes)})")
    kit = out_dir / KITS / name
    new = kit.with_name(f".{name}.new")
    shutil.rmtree(new, ignore_errors=True)
    try:
        for relative in (*KIT_FILES, *(f"nodes/{name}/{f}" for f in ("cert.pem", "key.pem", "permissions.p7s"))):
            target = new / relative
            target.parent.mkdir(parents=True, exist_ok=True)
            os.chmod(target.parent, 0o700)
            shutil.copy2(out_dir / relative, target)
        os.chmod(new, 0o700)
        shutil.rmtree(kit, ignore_errors=True)
        new.rename(kit)
    except OSError as error:
        shutil.rmtree(new, ignore_errors=True)
        raise CredentialsError(f"{kit}: cannot make node {name}'s kit: {error.strerror or error}") from None
    return kit


def describe(manifest: Manifest) -> list[str]:
    """What a credentials set holds, for people (never key material)."""
    d = manifest.directory
    lines = [
        f"credentials for mission {manifest.mission} in {d} (profile {manifest.profile})",
        f"  CA            {d / 'ca.pem'} (key {d / 'ca.key'}: keep it off the spacecraft)",
        f"  CRL           {d / 'crl.pem'}" + (f" (revoked: {', '.join(manifest.revoked)})" if manifest.revoked else ""),
        f"  governance    {d / 'governance.p7s'}",
    ]
    for name, entry in manifest.nodes.items():
        lines.append(f"  node {name:<8} {d / 'nodes' / name}/  address {entry['address']}, {entry['subject']}")
    for name, entry in manifest.tools.items():
        if name == OPERATOR:
            lines.append(f"  operator      {d / OPERATOR}/  {entry['subject']}, ground commands: "
                         f"{', '.join(entry.get('verbs') or [])} (key.pem: keep it on the ground)")
            continue
        lines.append(f"  tool {name:<8} {d / 'tools' / name}/  {entry['subject']} (subscribe only)")
    lines.append(f"  DDS tools     CYCLONEDDS_URI=file://{d / 'dds-tool.xml'}")
    lines.append(f"valid {manifest.not_before} .. {manifest.not_after} (expires {manifest.not_after})")
    return lines


__all__ = [
    "MISSION_KEY",
    "node_kit",
    "renew",
    "GROUND_VERBS",
    "ground_line",
    "COMMAND_TOPICS",
    "DEFAULT_DAYS",
    "DEFAULT_PROFILE",
    "MONITOR",
    "MONITOR_CN",
    "PROFILES",
    "TOPICS",
    "CredentialsError",
    "Manifest",
    "check_credentials",
    "describe",
    "ensure_credentials",
    "governance_xml",
    "make_credentials",
    "mission_nodes",
    "revoke",
    "security_section",
    "subject",
]
