"""DDS Security credentials (keel_cluster/security.py): every certificate is the CA's, every
signed document verifies, permissions say exactly what each role may do, keys stay private,
revocation reaches the CRL, and ensure_credentials reuses only a set that still fits the
mission. No keel-node is needed; openssl (the command) is."""

from __future__ import annotations

import ctypes.util
import datetime as dt
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from keel_cluster import cli, security
from keel_cluster.launcher import Cluster
from keel_cluster.security import CredentialsError

ROOT = Path(__file__).resolve().parents[2]
PROTOTYPE3 = ROOT / "config" / "prototype3.yaml"
EARTH_OBSERVATION = ROOT / "config" / "earth_observation.yaml"
PROTOTYPE3_IMAGE = ROOT / "tests" / "missions" / "images" / "good" / "prototype3.json"
ALL = set(security.TOPICS)

pytestmark = pytest.mark.skipif(shutil.which("openssl") is None, reason="the openssl command is not installed")


def openssl(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["openssl", *args], capture_output=True, text=True, check=check)


@pytest.fixture(scope="module")
def p3(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("p3") / "security"
    security.make_credentials(PROTOTYPE3, out)
    return out


@pytest.fixture(scope="module")
def eo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("eo") / "security"
    security.make_credentials(EARTH_OBSERVATION, out, profile="full", days=7)
    return out


def identities(out: Path) -> list[Path]:
    return sorted((out / "nodes").iterdir()) + [out / "tools" / "monitor"]


def signed_content(p7s: Path, ca: Path) -> str:
    done = openssl("smime", "-verify", "-in", str(p7s), "-CAfile", str(ca), check=False)
    assert done.returncode == 0, f"{p7s}: {done.stderr}"
    assert "Verification successful" in done.stderr
    return done.stdout.replace("\r\n", "\n")


def xml_of(path: Path) -> ET.Element:
    return ET.fromstring(path.read_text(encoding="utf-8"))


def cert_info(cert: Path) -> dict[str, str]:
    out = openssl("x509", "-in", str(cert), "-noout", "-subject", "-issuer", "-startdate", "-enddate",
                  "-nameopt", "RFC2253").stdout
    return {k.strip(): v.strip() for k, v in (line.split("=", 1) for line in out.splitlines())}


def xml_time(openssl_date: str) -> str:
    moment = dt.datetime.strptime(re.sub(r"\s+", " ", openssl_date), "%b %d %H:%M:%S %Y GMT")
    return moment.strftime("%Y-%m-%dT%H:%M:%S")


def rule(grant: ET.Element, kind: str) -> tuple[set[str], list[str]] | None:
    found = grant.find(f"allow_rule/{kind}")
    if found is None:
        return None
    return ({t.text or "" for t in found.iter("topic")}, [p.text or "" for p in found.iter("partition")])


# -- the layout and the certificates ------------------------------------------------------


@pytest.mark.parametrize("which", ["p3", "eo"])
def test_the_layout_is_complete(which: str, request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    for name in ("ca.pem", "ca.key", "crl.pem", "governance.xml", "governance.p7s", "dds-tool.xml",
                 "manifest.json"):
        assert (out / name).is_file(), name
    manifest = json.loads((out / "manifest.json").read_text())
    assert set(manifest) >= {"mission", "created_utc", "not_before", "not_after", "profile", "nodes", "tools"}
    assert sorted(p.name for p in (out / "nodes").iterdir()) == sorted(manifest["nodes"])
    for folder in identities(out):
        for name in ("cert.pem", "key.pem", "permissions.xml", "permissions.p7s"):
            assert (folder / name).is_file(), folder / name
    assert security.check_credentials(out, min_remaining_s=3600) == []


def test_addresses_are_the_mission_order() -> None:
    _, nodes = security.mission_nodes(EARTH_OBSERVATION)
    assert [(n.name, n.address) for n in nodes] == [("PN1", 0), ("PN2", 1), ("PN3", 2), ("PN4", 3),
                                                    ("ST1", 4), ("IF1", 5)]
    # An image says the same with its node ids (the address keel-node uses).
    image = json.loads(PROTOTYPE3_IMAGE.read_text())["content"]["nodes"]
    _, from_image = security.mission_nodes(PROTOTYPE3_IMAGE)
    assert [(n["name"], n["id"]) for n in image] == [(n.name, n.address) for n in from_image]
    assert [n.kind for n in from_image] == ["processing"] * 3 + ["interface"]


@pytest.mark.parametrize("which", ["p3", "eo"])
def test_every_certificate_is_the_cas(which: str, request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    manifest = json.loads((out / "manifest.json").read_text())
    ca = cert_info(out / "ca.pem")
    assert ca["subject"] == ca["issuer"]  # self-signed
    assert "CA:TRUE" in openssl("x509", "-in", str(out / "ca.pem"), "-noout", "-ext", "basicConstraints").stdout
    for folder in identities(out):
        cert = folder / "cert.pem"
        done = openssl("verify", "-CAfile", str(out / "ca.pem"), "-CRLfile", str(out / "crl.pem"), "-crl_check",
                       str(cert), check=False)
        assert done.returncode == 0 and f"{cert}: OK" in done.stdout, done.stdout + done.stderr
        info = cert_info(cert)
        expected = manifest["nodes"][folder.name]["subject"] if folder.parent.name == "nodes" else \
            manifest["tools"]["monitor"]["subject"]
        cn = folder.name if folder.parent.name == "nodes" else "keel-monitor"
        assert info["subject"] == expected == f"CN={cn},OU={manifest['mission']},O=Keel"
        assert info["issuer"] == ca["subject"]
        key = openssl("pkey", "-in", str(folder / "key.pem"), "-noout", "-text").stdout
        assert "prime256v1" in key
        assert (folder / "key.pem").read_text().startswith("-----BEGIN PRIVATE KEY-----")  # PKCS#8, unencrypted


def test_two_sets_do_not_trust_each_other(p3: Path, tmp_path: Path) -> None:
    other = tmp_path / "other"
    security.make_credentials(PROTOTYPE3, other)
    done = openssl("verify", "-CAfile", str(p3 / "ca.pem"), str(other / "nodes" / "PN1" / "cert.pem"), check=False)
    assert done.returncode != 0


@pytest.mark.parametrize("which", ["p3", "eo"])
def test_keys_are_private(which: str, request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    keys = [out / "ca.key", *(f / "key.pem" for f in identities(out))]
    for key in keys:
        assert key.stat().st_mode & 0o777 == 0o600, key
    assert (out / "ca.pem").stat().st_mode & 0o777 == 0o644


# -- signed documents -------------------------------------------------------------------


@pytest.mark.parametrize(("which", "profile", "kinds"), [
    ("p3", "encrypt", ("NONE", "SIGN", "ENCRYPT")),
    ("eo", "full", ("ENCRYPT", "ENCRYPT", "ENCRYPT")),
])
def test_governance(which: str, profile: str, kinds: tuple[str, str, str], request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    text = (out / "governance.xml").read_text()
    assert signed_content(out / "governance.p7s", out / "ca.pem").strip().endswith(text.strip())
    assert f'profile "{profile}"' in text
    rule_ = xml_of(out / "governance.xml").find("domain_access_rules/domain_rule")
    assert rule_ is not None
    assert rule_.findtext("domains/id_range/min") == "0" and rule_.findtext("domains/id_range/max") == "230"
    assert rule_.findtext("allow_unauthenticated_participants") == "false"
    assert rule_.findtext("enable_join_access_control") == "true"
    assert rule_.findtext("discovery_protection_kind") == "ENCRYPT"
    assert rule_.findtext("liveliness_protection_kind") == "ENCRYPT"
    assert rule_.findtext("rtps_protection_kind") == kinds[0]
    topics = rule_.findall("topic_access_rules/topic_rule")
    assert len(topics) == 1 and topics[0].findtext("topic_expression") == "*"
    for flag in ("enable_discovery_protection", "enable_liveliness_protection", "enable_read_access_control",
                 "enable_write_access_control"):
        assert topics[0].findtext(flag) == "true", flag
    assert (topics[0].findtext("metadata_protection_kind"), topics[0].findtext("data_protection_kind")) == kinds[1:]


def test_the_sign_profile() -> None:
    text = security.governance_xml("sign")
    assert "<rtps_protection_kind>NONE</rtps_protection_kind>" in text
    assert "<metadata_protection_kind>SIGN</metadata_protection_kind>" in text
    assert "<data_protection_kind>SIGN</data_protection_kind>" in text
    assert "ENCRYPT</data_protection_kind>" not in text


def test_a_tampered_document_does_not_verify(p3: Path, tmp_path: Path) -> None:
    tampered = tmp_path / "permissions.p7s"
    text = (p3 / "nodes" / "ST1" / "permissions.p7s").read_text()
    assert "<topic>KeelData</topic>" in text
    tampered.write_text(text.replace("<topic>KeelData</topic>", "<topic>KeelCommand</topic>", 1))
    done = openssl("smime", "-verify", "-in", str(tampered), "-CAfile", str(p3 / "ca.pem"), check=False)
    assert done.returncode != 0


@pytest.mark.parametrize("which", ["p3", "eo"])
def test_permissions_match_the_certificates(which: str, request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    for folder in identities(out):
        text = (folder / "permissions.xml").read_text()
        assert signed_content(folder / "permissions.p7s", out / "ca.pem").strip().endswith(text.strip())
        grants = xml_of(folder / "permissions.xml").findall("permissions/grant")
        assert len(grants) == 1
        grant = grants[0]
        info = cert_info(folder / "cert.pem")
        assert grant.findtext("subject_name") == info["subject"]
        assert grant.findtext("validity/not_before") == xml_time(info["notBefore"])
        assert grant.findtext("validity/not_after") == xml_time(info["notAfter"])
        assert grant.findtext("default") == "DENY"
        assert grant.findtext("allow_rule/domains/id_range/min") == "0"
        assert grant.findtext("allow_rule/domains/id_range/max") == "230"


def test_roles(eo: Path) -> None:
    manifest = json.loads((eo / "manifest.json").read_text())
    kinds = {name: entry["kind"] for name, entry in manifest["nodes"].items()}
    assert kinds == {"PN1": "processing", "PN2": "processing", "PN3": "processing", "PN4": "processing",
                     "ST1": "interface", "IF1": "interface"}
    for name, entry in manifest["nodes"].items():
        grant = xml_of(eo / "nodes" / name / "permissions.xml").find("permissions/grant")
        assert grant is not None
        address = entry["address"]
        publish, subscribe = rule(grant, "publish"), rule(grant, "subscribe")
        assert publish is not None and subscribe is not None
        if entry["kind"] == "processing":
            assert publish[0] == ALL, name
        else:  # storage and interface nodes do not command
            assert "KeelCommand" not in publish[0], name
            assert publish[0] == ALL - {"KeelCommand"}, name
        assert publish[1] == [f"keel.from.{address}", "keel.node.*", "keel.broadcast"]
        assert subscribe[0] == ALL
        # Samples addressed to another node are not this node's to read.
        assert subscribe[1] == ["keel.from.*", f"keel.node.{address}", "keel.broadcast"]


@pytest.mark.parametrize("which", ["p3", "eo"])
def test_the_monitor_only_listens(which: str, request: pytest.FixtureRequest) -> None:
    out: Path = request.getfixturevalue(which)
    grant = xml_of(out / "tools" / "monitor" / "permissions.xml").find("permissions/grant")
    assert grant is not None
    assert rule(grant, "publish") is None
    assert grant.find("allow_rule/publish") is None
    assert rule(grant, "subscribe") == (ALL, ["*"])
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["tools"]["monitor"]["publishes"] is False


def test_the_operator_is_the_cas_with_its_own_grant_and_signs_ground_commands(p3: Path, tmp_path: Path) -> None:
    # The ground's operator (docs/operations.md): an identity of the CA's, never a node's,
    # with a CA-signed grant naming the ground commands it may send; ground_line signs a
    # command with its key, which verifies with its certificate and with no node's.
    operator = p3 / security.OPERATOR
    assert openssl("verify", "-CAfile", str(p3 / "ca.pem"), str(operator / "cert.pem")).returncode == 0
    assert cert_info(operator / "cert.pem")["subject"] == security.subject(security.OPERATOR_CN, "prototype3")
    assert (operator / "key.pem").stat().st_mode & 0o077 == 0
    grant = signed_content(operator / "permissions.p7s", p3 / "ca.pem")
    assert f"<subject_name>{security.subject(security.OPERATOR_CN, 'prototype3')}</subject_name>" in grant
    assert "<verbs>phase recover exclude readmit pause-task resume-task designate</verbs>" in grant
    manifest = json.loads((p3 / "manifest.json").read_text())
    assert manifest["tools"]["operator"]["verbs"] == list(security.GROUND_VERBS)
    assert any(line.strip().startswith("operator") for line in security.describe(security.Manifest.load(p3)))
    line = security.ground_line(p3, "ab" * 32, 12, "phase", "science")
    word, signature, text = line.split(" ", 2)
    assert (word, text) == ("ground", "keel-ground/1 image=abababababababab seq=12 phase science")
    (tmp_path / "text").write_text(text)
    (tmp_path / "sig").write_bytes(bytes.fromhex(signature))
    for cert, verifies in ((operator / "cert.pem", True), (p3 / "nodes" / "PN1" / "cert.pem", False)):
        openssl("x509", "-in", str(cert), "-pubkey", "-noout", "-out", str(tmp_path / "pub.pem"))
        done = openssl("dgst", "-sha256", "-verify", str(tmp_path / "pub.pem"), "-signature",
                       str(tmp_path / "sig"), str(tmp_path / "text"), check=False)
        assert (done.returncode == 0) == verifies, (cert, done.stdout, done.stderr)
    with pytest.raises(CredentialsError, match="not a ground command"):
        security.ground_line(p3, "ab" * 32, 13, "reboot", "PN2")


def test_the_operators_grant_can_be_narrowed_and_names_only_known_commands(tmp_path: Path) -> None:
    out = tmp_path / "narrow"
    security.make_credentials(PROTOTYPE3, out, operator_verbs=["phase"])
    assert "<verbs>phase</verbs>" in signed_content(out / "operator" / "permissions.p7s", out / "ca.pem")
    with pytest.raises(CredentialsError, match="unknown ground command 'reboot'"):
        security.make_credentials(PROTOTYPE3, tmp_path / "bad", operator_verbs=["phase", "reboot"])
    # A set made before the operator existed is not reused: ensure_credentials makes a new one.
    shutil.rmtree(out / "operator")
    assert not security.reusable(security.Manifest.load(out), *security.mission_nodes(PROTOTYPE3), "encrypt")


# -- the DDS tool configuration ---------------------------------------------------------------


def test_dds_tool_configuration(p3: Path) -> None:
    root = xml_of(p3 / "dds-tool.xml")
    domain = root.find("Domain")
    assert domain is not None and domain.get("Id") == "any"
    assert domain.find("General/Interfaces/NetworkInterface").get("name") == "lo"  # type: ignore[union-attr]
    assert domain.findtext("General/AllowMulticast") == "false"
    assert domain.findtext("Discovery/ParticipantIndex") == "auto"
    assert domain.find("Discovery/Peers/Peer").get("address") == "127.0.0.1"  # type: ignore[union-attr]
    expected = {
        "Authentication/IdentityCertificate": p3 / "tools" / "monitor" / "cert.pem",
        "Authentication/IdentityCA": p3 / "ca.pem",
        "Authentication/PrivateKey": p3 / "tools" / "monitor" / "key.pem",
        "Authentication/CRL": p3 / "crl.pem",
        "AccessControl/Governance": p3 / "governance.p7s",
        "AccessControl/PermissionsCA": p3 / "ca.pem",
        "AccessControl/Permissions": p3 / "tools" / "monitor" / "permissions.p7s",
    }
    for element, path in expected.items():
        assert domain.findtext(f"Security/{element}") == f"file:{path.resolve()}", element
        assert path.is_file()
    # Element names as Cyclone DDS 0.10 knows them (ddsi_cfgelems.h), where it is installed.
    header = Path("/usr/include/dds/ddsi/ddsi_cfgelems.h")
    if header.is_file():
        known = header.read_text(errors="replace")
        for element in domain.iter():
            if element.tag not in ("Domain",):
                assert f'"{element.tag}"' in known or f'"{element.tag}|' in known, element.tag


def _libddsc() -> str | None:
    for name in ("libddsc.so.0debian", "libddsc.so.0", ctypes.util.find_library("ddsc")):
        if not name:
            continue
        try:
            ctypes.CDLL(name)
            return name
        except OSError:
            continue
    return None


PARTICIPANT = """
import ctypes, sys
lib = ctypes.CDLL(sys.argv[1])
lib.dds_create_participant.restype = ctypes.c_int32
p = lib.dds_create_participant(ctypes.c_uint32(int(sys.argv[2])), None, None)
if p > 0:
    lib.dds_delete(p)
sys.exit(0 if p > 0 else 1)
"""


def participant(config: Path, domain: int) -> subprocess.CompletedProcess[str]:
    """Creates and deletes one DDS participant with `config` (no cluster): Cyclone's
    security plugins check the identity, the CRL, the governance and the permissions."""
    library = _libddsc()
    assert library is not None
    env = dict(os.environ, CYCLONEDDS_URI=f"file://{config}")
    return subprocess.run([sys.executable, "-c", PARTICIPANT, library, str(domain)], capture_output=True,
                          text=True, timeout=30, env=env, check=False)


@pytest.mark.skipif(_libddsc() is None or not any(d.is_dir() for d in security.PLUGIN_DIRS),
                    reason="Cyclone DDS with its security plugins is not installed")
def test_cyclone_accepts_the_credentials(tmp_path: Path) -> None:
    out = tmp_path / "security"
    security.make_credentials(EARTH_OBSERVATION, out)
    tool = out / "dds-tool.xml"
    assert participant(tool, 230).returncode == 0, participant(tool, 230).stderr
    # A node's identity: its subject matches its permissions.
    node = tmp_path / "ST1.xml"
    node.write_text(tool.read_text().replace("/tools/monitor/", "/nodes/ST1/"))
    assert participant(node, 230).returncode == 0
    # Someone else's permissions with this identity: refused.
    mixed = tmp_path / "mixed.xml"
    mixed.write_text(tool.read_text().replace("tools/monitor/permissions.p7s", "nodes/PN1/permissions.p7s"))
    done = participant(mixed, 230)
    assert done.returncode != 0 and "Subject name is invalid" in done.stderr
    # A domain the governance does not cover: refused.
    done = participant(tool, 231)
    assert done.returncode != 0 and "governance" in done.stderr
    # A revoked identity: refused.
    security.revoke(out, "ST1")
    done = participant(node, 230)
    assert done.returncode != 0 and "revoked" in done.stderr


# -- revocation, reuse, expiry ----------------------------------------------------------------


def test_revoke(tmp_path: Path) -> None:
    out = tmp_path / "security"
    security.make_credentials(PROTOTYPE3, out)
    assert "No Revoked Certificates" in openssl("crl", "-in", str(out / "crl.pem"), "-noout", "-text").stdout
    serial = openssl("x509", "-in", str(out / "nodes" / "PN2" / "cert.pem"), "-noout", "-serial").stdout
    serial = serial.strip().split("=")[1]
    manifest = security.revoke(out, "PN2")
    assert manifest.revoked == ["PN2"]
    crl = openssl("crl", "-in", str(out / "crl.pem"), "-noout", "-text", "-CAfile", str(out / "ca.pem")).stdout
    assert re.search(rf"Serial Number: 0*{serial}\b", crl), crl
    assert crl.count("Serial Number:") == 1
    for name, ok in (("PN2", False), ("PN1", True)):
        done = openssl("verify", "-CAfile", str(out / "ca.pem"), "-CRLfile", str(out / "crl.pem"), "-crl_check",
                       str(out / "nodes" / name / "cert.pem"), check=False)
        assert (done.returncode == 0) is ok, name
    # Revoking twice changes nothing; the set is still reused (the revocation stays).
    security.revoke(out, "PN2")
    assert openssl("crl", "-in", str(out / "crl.pem"), "-noout", "-text").stdout.count("Serial Number:") == 1
    again = security.ensure_credentials(PROTOTYPE3, out)
    assert again.revoked == ["PN2"]
    with pytest.raises(CredentialsError, match="no node or tool 'XX'"):
        security.revoke(out, "XX")


def test_ensure_reuses_a_fitting_set(tmp_path: Path) -> None:
    out = tmp_path / "security"
    first = security.ensure_credentials(PROTOTYPE3, out)
    ca = (out / "ca.pem").read_bytes()
    second = security.ensure_credentials(PROTOTYPE3, out)
    assert second.created_utc == first.created_utc and (out / "ca.pem").read_bytes() == ca
    # The same mission as an image: the same nodes, addresses and subjects.
    security.ensure_credentials(PROTOTYPE3_IMAGE, out)
    assert (out / "ca.pem").read_bytes() == ca
    # Another profile: a new set.
    security.ensure_credentials(PROTOTYPE3, out, profile="sign")
    assert (out / "ca.pem").read_bytes() != ca
    assert json.loads((out / "manifest.json").read_text())["profile"] == "sign"
    assert "<data_protection_kind>SIGN</data_protection_kind>" in (out / "governance.xml").read_text()
    ca = (out / "ca.pem").read_bytes()
    # Another node set: a new set.
    smaller = tmp_path / "smaller.yaml"
    smaller.write_text(PROTOTYPE3.read_text().replace("  ST1: {kind: interface", "  XS1: {kind: interface"))
    made = security.ensure_credentials(smaller, out, profile="sign")
    assert set(made.nodes) == {"PN1", "PN2", "PN3", "XS1"} and (out / "ca.pem").read_bytes() != ca
    assert not (out / "nodes" / "ST1").exists()
    ca = (out / "ca.pem").read_bytes()
    # A damaged set (a key others can read): a new set.
    os.chmod(out / "nodes" / "PN1" / "key.pem", 0o644)
    assert any("readable by others" in p for p in security.check_credentials(out))
    security.ensure_credentials(smaller, out, profile="sign")
    assert (out / "ca.pem").read_bytes() != ca
    assert (out / "nodes" / "PN1" / "key.pem").stat().st_mode & 0o777 == 0o600
    # No stray work folders are left beside it.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["security", "smaller.yaml"]


def test_an_expired_set_is_regenerated(tmp_path: Path) -> None:
    out = tmp_path / "security"
    long_ago = dt.datetime.now(dt.UTC) - dt.timedelta(days=400)
    old = security.make_credentials(PROTOTYPE3, out, days=2, not_before=long_ago)
    problems = security.check_credentials(out)
    assert problems and all("expire" in p for p in problems)
    assert openssl("verify", "-CAfile", str(out / "ca.pem"), str(out / "nodes" / "PN1" / "cert.pem"),
                   check=False).returncode != 0
    new = security.ensure_credentials(PROTOTYPE3, out)
    assert new.not_after != old.not_after and security.check_credentials(out, min_remaining_s=3600) == []
    assert new.expires - dt.datetime.now(dt.UTC) > dt.timedelta(days=29)


def test_a_set_about_to_expire_is_regenerated(tmp_path: Path) -> None:
    out = tmp_path / "security"
    # Valid for another 30 minutes: less than the hour ensure_credentials asks for.
    start = dt.datetime.now(dt.UTC) - dt.timedelta(days=1) + dt.timedelta(minutes=30)
    old = security.make_credentials(PROTOTYPE3, out, days=1, not_before=start)
    assert security.check_credentials(out) == []
    assert security.check_credentials(out, min_remaining_s=3600) != []
    new = security.ensure_credentials(PROTOTYPE3, out)
    assert new.created_utc != old.created_utc or new.not_after != old.not_after
    assert security.check_credentials(out, min_remaining_s=3600) == []


# -- bad inputs -------------------------------------------------------------------------------


def test_bad_inputs_name_the_file(tmp_path: Path) -> None:
    with pytest.raises(CredentialsError, match=r"missing\.yaml: cannot read the mission"):
        security.make_credentials(tmp_path / "missing.yaml", tmp_path / "out")
    junk = tmp_path / "junk.yaml"
    junk.write_text("a: [\n")
    with pytest.raises(CredentialsError, match=r"junk\.yaml: not a mission"):
        security.make_credentials(junk, tmp_path / "out")
    nonodes = tmp_path / "nonodes.yaml"
    nonodes.write_text("mission: x\nnodes: {}\n")
    with pytest.raises(CredentialsError, match=r"nonodes\.yaml: not a mission \(no `nodes`\)"):
        security.make_credentials(nonodes, tmp_path / "out")
    with pytest.raises(CredentialsError, match="unknown profile 'secret'"):
        security.make_credentials(PROTOTYPE3, tmp_path / "out", profile="secret")
    quoted = ROOT / "tests" / "missions" / "good" / "everything.yaml"
    with pytest.raises(CredentialsError, match="cannot go into a certificate subject"):
        security.make_credentials(quoted, tmp_path / "out")
    # A folder that holds something else is not replaced.
    other = tmp_path / "other"
    other.mkdir()
    (other / "precious.txt").write_text("keep")
    with pytest.raises(CredentialsError, match="not a credentials set"):
        security.make_credentials(PROTOTYPE3, other)
    assert (other / "precious.txt").read_text() == "keep"
    assert not (tmp_path / "out").exists()


def test_openssl_missing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    with pytest.raises(CredentialsError, match="openssl command is not installed"):
        security.make_credentials(PROTOTYPE3, tmp_path / "out")


def test_openssl_failing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fake = tmp_path / "bin" / "openssl"
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\necho 'error:0480006C:PEM routines::no start line' >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake.parent}:{os.environ['PATH']}")
    with pytest.raises(CredentialsError) as caught:
        security.make_credentials(PROTOTYPE3, tmp_path / "out")
    message = str(caught.value)
    assert "\n" not in message and "openssl genpkey failed (exit 1)" in message and str(tmp_path / "out") in message
    assert not (tmp_path / "out").exists() and [p.name for p in tmp_path.iterdir()] == ["bin"]


def test_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "creds"
    assert cli.main(["credentials", str(EARTH_OBSERVATION), "--out", str(out), "--days", "3",
                     "--profile", "sign"]) == 0
    printed = capsys.readouterr().out
    assert str(out / "nodes" / "IF1") in printed and str(out / "dds-tool.xml") in printed
    manifest = json.loads((out / "manifest.json").read_text())
    assert f"expires {manifest['not_after']}" in printed
    assert "PRIVATE KEY" not in printed
    assert cli.main(["credentials", str(EARTH_OBSERVATION), "--out", str(out), "--revoke", "IF1"]) == 0
    assert "revoked IF1" in capsys.readouterr().out
    # A renewal says what to do with what it made: a node restarts with its own; every node
    # needs the operator's new certificate and grant (it loads them at start).
    assert cli.main(["credentials", str(EARTH_OBSERVATION), "--out", str(out), "--renew", "PN2"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith(f"renewed PN2: a new key, certificate and grant in {out / 'nodes' / 'PN2'}")
    assert "give them to the node and restart it" in printed
    assert cli.main(["credentials", str(EARTH_OBSERVATION), "--out", str(out), "--renew", "operator"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith(f"renewed the operator: a new key, certificate and grant in {out / 'operator'}")
    assert "give every node the new cert.pem and grant" in printed and "to the node" not in printed
    assert "Serial Number" in openssl("crl", "-in", str(out / "crl.pem"), "-noout", "-text").stdout
    for argv in (["credentials", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "x")],
                 ["credentials", str(EARTH_OBSERVATION), "--out", str(out), "--revoke", "NOBODY"],
                 ["credentials", str(EARTH_OBSERVATION), "--out", str(tmp_path / "x"), "--days", "0"]):
        assert cli.main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("keel-cluster credentials: ") and err.count("\n") == 1 and "Traceback" not in err
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert cli.main(["credentials", str(PROTOTYPE3), "--out", str(tmp_path / "y")]) == 2
    assert "openssl command is not installed" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exited:
        cli.main(["run", str(PROTOTYPE3), "--insecure", "--security-profile", "full"])
    assert exited.value.code == 2
    for domain in ("233", "-1", "seven"):
        with pytest.raises(SystemExit) as exited:
            cli.main(["run", str(PROTOTYPE3), "--insecure", "--domain", domain])
        assert exited.value.code == 2
        assert "not a DDS domain id (0..232)" in capsys.readouterr().err


# -- the launcher ---------------------------------------------------------------------------


def test_a_secured_cluster_flies_an_image_signed_with_the_missions_key(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Signed images are the default: the credentials set holds the mission's Ed25519 key
    # (mission/signing.key, the ground's), the launcher compiles the image signed with it,
    # and every node gets the public key from its kit (--public-key). An image given
    # already compiled, unsigned, flies as it is (no --public-key); an insecure run signs
    # nothing.
    from keel_verify.image import key_id, load_public_key

    monkeypatch.delenv("KEEL_SIGNING_KEY", raising=False)
    monkeypatch.setattr(Cluster, "start", lambda self, name: None)
    run_dir = tmp_path / "run"
    with Cluster(PROTOTYPE3, ["PN1", "ST1"], run_dir, Path("/bin/true"), echo=False) as cluster:
        assert cluster.image_path is not None and cluster.security_dir is not None
        public = cluster.security_dir / "mission" / "signing.pub"
        signature = json.loads(cluster.image_path.read_text())["signature"]
        assert signature["key_id"] == key_id(load_public_key(public))
        for name, node in cluster.nodes.items():
            at = node.argv.index("--public-key")
            assert node.argv[at + 1] == str(cluster.security_dir / "kits" / name / "mission" / "signing.pub")
        assert (cluster.security_dir / "mission" / "signing.key").stat().st_mode & 0o077 == 0
        kit = security.node_kit(cluster.security_dir, "PN1")
        assert (kit / "mission" / "signing.pub").read_bytes() == public.read_bytes()
        assert not (kit / "mission" / "signing.key").exists()
    with Cluster(PROTOTYPE3_IMAGE, ["PN1"], tmp_path / "given", Path("/bin/true"), echo=False) as cluster:
        assert "--public-key" not in cluster.nodes["PN1"].argv
    with Cluster(PROTOTYPE3, ["PN1"], tmp_path / "insecure", Path("/bin/true"), echo=False,
                 insecure=True) as cluster:
        assert "--public-key" not in cluster.nodes["PN1"].argv
        assert cluster.image_path is not None and "signature" not in json.loads(cluster.image_path.read_text())


def test_the_cluster_secures_its_nodes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    started: list[str] = []
    monkeypatch.setattr(Cluster, "start", lambda self, name: started.append(name))
    run_dir = tmp_path / "run"
    binary = Path("/bin/true")
    with Cluster(PROTOTYPE3_IMAGE, ["PN1", "PN2", "PN3", "ST1"], run_dir, binary, echo=False,
                 security_profile="full") as cluster:
        assert started == ["PN1", "PN2", "PN3", "ST1"]
        for name, node in cluster.nodes.items():
            at = node.argv.index("--security")
            assert node.argv[at + 1] == str((run_dir / "security" / "kits" / name).resolve()), name
            assert "--insecure" not in node.argv
        assert cluster.credentials.profile == "full"
    assert security.check_credentials(run_dir / "security", min_remaining_s=3600) == []
    created = json.loads((run_dir / "security" / "manifest.json").read_text())["created_utc"]
    # The next cluster in the same run directory reuses them.
    with Cluster(PROTOTYPE3_IMAGE, ["PN1"], run_dir, binary, echo=False, security_profile="full"):
        pass
    assert json.loads((run_dir / "security" / "manifest.json").read_text())["created_utc"] == created
    insecure_dir = tmp_path / "insecure"
    with Cluster(PROTOTYPE3_IMAGE, ["PN1", "PN2"], insecure_dir, binary, echo=False, insecure=True) as cluster:
        for node in cluster.nodes.values():
            assert "--insecure" in node.argv and "--security" not in node.argv
    assert not (insecure_dir / "security").exists()
