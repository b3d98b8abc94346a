"""The proven mission image: its canonical encoding, its hash and signature, and the
checks a loader makes before it flies one.

``keel-verify compile`` writes an image; a node loads it. An image is one JSON object
(``config/schema/image.schema.json``) whose ``content`` is the fully resolved mission that
was proved. Its ``sha256`` is the SHA-256 of the canonical encoding of the object without
its ``sha256`` and ``signature`` fields; the optional Ed25519 ``signature`` signs those same
bytes. The canonical encoding (sorted keys, no whitespace, UTF-8, shortest round-trip
floats, no NaN or infinity) is specified in ``config/schema/README.md``, for every reader
that checks a hash; :func:`canonical_bytes` implements it.

``load_image(path, public_key)`` makes the checks, in this order, and raises
:class:`ImageError` naming the first that fails: the file reads as JSON (no duplicate
keys, no NaN), the format version, the hash, the signature (when a public key is
given), the schema (and floats only where a mission has them: JSON Schema counts 3.0 as
an integer), the consistency of ids and name, and the capacity. ``keel-verify
image-check`` runs it from the command line.
"""

from __future__ import annotations

import argparse
import base64
import binascii
import hashlib
import json
import math
import sys
from functools import lru_cache
from pathlib import Path
from typing import Any

import jsonschema_rs

from keel_verify import limits, resources

# The image format this verifier writes and reads. A loader refuses every other version.
FORMAT_VERSION = 1

# The image's JSON Schema, config/schema/image.schema.json (keel_verify.resources).
SCHEMA_NAME = "image.schema.json"

# The fields the hash does not cover: the hash itself, and the signature over the same bytes.
UNHASHED_FIELDS = ("sha256", "signature")

SIGNATURE_ALGORITHM = "ed25519"
KEY_ID_HEX_DIGITS = 16

# A loader reads at most this much; compile refuses to write a larger image.
MAX_IMAGE_BYTES = 64 * 1024 * 1024

EXIT_OK = 0
EXIT_INVALID = 2


class ImageError(Exception):
    """An image a loader must refuse; ``reason`` is a stable id (config/schema/README.md)."""

    def __init__(self, file: str, reason: str, message: str):
        self.file = file
        self.reason = reason
        self.message = message
        super().__init__(f"{file}: {reason}: {message}")


class KeyFileError(Exception):
    """A signing or public key file that cannot be used."""


# --------------------------------------------------------------------------------------
# Canonical encoding, hash, signature


def canonical_bytes(value: Any) -> bytes:
    """The canonical encoding described in the module's docstring."""
    text = json.dumps(
        value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
    )
    return text.encode("utf-8")


def hashed_bytes(image: dict[str, Any]) -> bytes:
    """The bytes the hash and the signature cover."""
    return canonical_bytes({k: v for k, v in image.items() if k not in UNHASHED_FIELDS})


def content_hash(image: dict[str, Any]) -> str:
    return hashlib.sha256(hashed_bytes(image)).hexdigest()


def _crypto() -> Any:
    """The Ed25519 primitives of the ``cryptography`` package, imported when first needed
    so that unsigned images need nothing beyond the verifier's other dependencies."""
    try:
        from cryptography.hazmat.primitives.asymmetric import ed25519
    except ModuleNotFoundError:
        raise KeyFileError(
            "Ed25519 needs the Python package 'cryptography' (./keel setup installs it)"
        ) from None
    return ed25519


def _read_key_file(path: str | Path) -> bytes:
    try:
        with open(path, "rb") as stream:
            return stream.read(64 * 1024)
    except OSError as error:
        raise KeyFileError(f"{path}: cannot read: {error.strerror}") from None


def load_signing_key(path: str | Path) -> Any:
    """An Ed25519 private key from a PEM file (``openssl genpkey -algorithm ed25519``)."""
    ed25519 = _crypto()
    from cryptography.hazmat.primitives import serialization

    data = _read_key_file(path)
    try:
        key = serialization.load_pem_private_key(data, password=None)
    except TypeError:
        raise KeyFileError(f"{path}: the key is encrypted; give an unencrypted PEM key") from None
    except ValueError:
        raise KeyFileError(
            f"{path}: not a PEM private key "
            "(make one with: openssl genpkey -algorithm ed25519 -out mission.key)"
        ) from None
    except Exception as error:  # cryptography's UnsupportedAlgorithm and kin
        raise KeyFileError(f"{path}: cannot use the key: {error}") from None
    if not isinstance(key, ed25519.Ed25519PrivateKey):
        raise KeyFileError(f"{path}: not an Ed25519 key (mission images are signed with Ed25519)")
    return key


def load_public_key(path: str | Path) -> Any:
    """An Ed25519 public key from a PEM file (``openssl pkey -in KEY -pubout``)."""
    ed25519 = _crypto()
    from cryptography.hazmat.primitives import serialization

    data = _read_key_file(path)
    try:
        key = serialization.load_pem_public_key(data)
    except ValueError:
        hint = " (this file holds a private key)" if b"PRIVATE KEY" in data else ""
        raise KeyFileError(
            f"{path}: not a PEM public key{hint}; make one with: "
            "openssl pkey -in mission.key -pubout -out mission.pub"
        ) from None
    except Exception as error:  # cryptography's UnsupportedAlgorithm and kin
        raise KeyFileError(f"{path}: cannot use the key: {error}") from None
    if not isinstance(key, ed25519.Ed25519PublicKey):
        raise KeyFileError(f"{path}: not an Ed25519 public key")
    return key


def key_id(public_key: Any) -> str:
    """The first 16 hex digits of the SHA-256 of the raw 32-byte public key."""
    from cryptography.hazmat.primitives import serialization

    raw = public_key.public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    return hashlib.sha256(raw).hexdigest()[:KEY_ID_HEX_DIGITS]


def seal(image: dict[str, Any], signing_key: Any = None) -> dict[str, Any]:
    """The image with its ``sha256`` and, given a key, its ``signature``."""
    body = {k: v for k, v in image.items() if k not in UNHASHED_FIELDS}
    message = canonical_bytes(body)
    sealed = dict(body, sha256=hashlib.sha256(message).hexdigest())
    if signing_key is not None:
        sealed["signature"] = {
            "alg": SIGNATURE_ALGORITHM,
            "key_id": key_id(signing_key.public_key()),
            "value": base64.b64encode(signing_key.sign(message)).decode("ascii"),
        }
    return sealed


def encode_file(image: dict[str, Any]) -> bytes:
    """An image file: the canonical encoding of the whole image and one line feed."""
    return canonical_bytes(image) + b"\n"


# --------------------------------------------------------------------------------------
# Schema


@lru_cache(maxsize=1)
def _validator() -> Any:
    schema = json.loads(resources.schema_path(SCHEMA_NAME).read_text(encoding="utf-8"))
    return jsonschema_rs.Draft202012Validator(schema)


def _where(path: Any) -> str:
    return ".".join(str(p) for p in path) or "the image"


def _float_allowed(path: tuple[Any, ...]) -> bool:
    """Where a mission holds floats: health bounds and params values."""
    if path[:2] == ("content", "tasks"):
        return (len(path) == 5 and path[3] == "health" and path[4] in ("min", "max")) or (
            len(path) == 5 and path[3] == "params"
        )
    return path[:2] == ("content", "phases") and len(path) == 6 and path[3] == "params"


def _float_errors(image: Any) -> list[str]:
    """JSON Schema counts 3.0 as an integer; an image holds an integer token wherever the
    mission holds an integer, and a float only where the mission has floats."""
    errors: list[str] = []
    if not isinstance(image, (dict, list)):
        return errors  # the schema has said what is wrong with it
    # Paths are made for collections and floats only: most values are neither.
    stack: list[tuple[tuple[Any, ...], Any]] = [((), image)]
    while stack:
        path, collection = stack.pop()
        items = collection.items() if isinstance(collection, dict) else enumerate(collection)
        for key, value in items:
            if isinstance(value, (dict, list)):
                stack.append((path + (key,), value))
            elif isinstance(value, float) and not _float_allowed(path + (key,)):
                where = _where(path + (key,))
                errors.append(f"{where}: {value!r} is a float where an integer is expected")
    return errors


def schema_errors(image: Any) -> list[str]:
    """Every place the image breaks image.schema.json, as ``where: message``, in order of
    position."""
    try:
        found = [(list(map(str, e.instance_path)), f"{_where(e.instance_path)}: {e.message}")
                 for e in _validator().iter_errors(image)]
    except ValueError as error:  # the validator's own limits, e.g. on nesting
        return [f"the image: {error}"]
    if not found:
        found = [([], message) for message in _float_errors(image)]
    return [message for _, message in sorted(found)]


# --------------------------------------------------------------------------------------
# Loading


def _refuse_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            # Two JSON readers may keep different ones of two equal keys.
            raise ValueError(f"duplicate key '{key}'")
        result[key] = value
    return result


def _finite_float(text: str) -> float:
    value = float(text)
    if math.isinf(value):
        raise ValueError(f"number {text[:40]} is out of the range of a double")
    return value


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")


def _parse(file: str, raw: bytes) -> Any:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ImageError(file, "not-json", f"not UTF-8 text (byte {error.start})") from None
    try:
        value = json.loads(
            text, object_pairs_hook=_refuse_duplicates, parse_constant=_refuse_constant,
            parse_float=_finite_float,
        )
        # A \ud800-style escape decodes to a lone surrogate, which no UTF-8 text holds.
        json.dumps(value, ensure_ascii=False).encode("utf-8")
        return value
    except UnicodeEncodeError:
        raise ImageError(file, "not-json", "a string escapes a lone UTF-16 surrogate") from None
    except json.JSONDecodeError as error:
        raise ImageError(
            file, "not-json", f"line {error.lineno} column {error.colno}: {error.msg}"
        ) from None
    except (ValueError, RecursionError) as error:
        raise ImageError(file, "not-json", str(error) or "nested too deeply") from None


def _check_version(file: str, image: Any) -> None:
    if not isinstance(image, dict) or "keel_image" not in image:
        raise ImageError(
            file, "format-version", "not a Keel mission image (no keel_image field at the top)"
        )
    version = image["keel_image"]
    if type(version) is not int or version != FORMAT_VERSION:
        raise ImageError(
            file,
            "format-version",
            f"image format {json.dumps(version)}; this loader reads format {FORMAT_VERSION} "
            "(compile the mission again with this keel-verify)",
        )


def _check_hash(file: str, image: dict[str, Any]) -> None:
    recorded = image.get("sha256")
    if not isinstance(recorded, str):
        raise ImageError(file, "tampered", "the image carries no sha256 of its content")
    computed = content_hash(image)
    if recorded != computed:
        raise ImageError(
            file,
            "tampered",
            f"sha256 mismatch: the image records {recorded} but its content hashes to "
            f"{computed}; it was changed after it was compiled",
        )


def _check_signature(file: str, image: dict[str, Any], public_key: Any) -> None:
    expected_id = key_id(public_key)
    signature = image.get("signature")
    if signature is None:
        raise ImageError(
            file,
            "unsigned",
            f"the image is not signed, and a public key (key id {expected_id}) was given",
        )
    if not isinstance(signature, dict) or signature.get("alg") != SIGNATURE_ALGORITHM:
        raise ImageError(file, "bad-signature", f"the signature is not an {SIGNATURE_ALGORITHM} "
                         "signature object")
    if signature.get("key_id") != expected_id:
        raise ImageError(
            file,
            "wrong-key",
            f"signed with key id {signature.get('key_id')}, but the public key given has "
            f"key id {expected_id}",
        )
    try:
        value = base64.b64decode(str(signature.get("value", "")), validate=True)
    except (binascii.Error, ValueError):
        raise ImageError(file, "bad-signature", "the signature value is not base64") from None
    from cryptography.exceptions import InvalidSignature

    try:
        public_key.verify(value, hashed_bytes(image))
    except InvalidSignature:
        raise ImageError(
            file,
            "bad-signature",
            f"the Ed25519 signature does not verify with key id {expected_id}",
        ) from None


def _check_schema(file: str, image: dict[str, Any]) -> None:
    errors = schema_errors(image)
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise ImageError(file, "schema", f"{errors[0]}{more}")


def _check_consistency(file: str, image: dict[str, Any]) -> None:
    content = image["content"]
    if content["mission"] != image["mission"]:
        raise ImageError(file, "inconsistent",
                         f"mission {image['mission']!r} but content.mission "
                         f"{content['mission']!r}")
    for what in ("nodes", "tasks"):
        for index, item in enumerate(content[what]):
            if item["id"] != index:
                raise ImageError(
                    file,
                    "inconsistent",
                    f"content.{what}.{index} ({item['name']}) has id {item['id']}; "
                    f"the id of an entry is its index",
                )


def _check_capacity(file: str, image: dict[str, Any]) -> None:
    content = image["content"]
    declared = image["capacity"]
    for what, ours, theirs in (
        ("nodes", limits.MAX_NODES, declared["max_nodes"]),
        ("tasks", limits.MAX_TASKS, declared["max_tasks"]),
    ):
        count = len(content[what])
        limit = min(ours, theirs)
        if count > limit:
            holder = "this loader" if ours <= theirs else "the image's own capacity"
            raise ImageError(
                file,
                "over-limit",
                f"the image has {count} {what}; {holder} allows at most {limit}",
            )


def load_image(path: str | Path, public_key: Any = None) -> dict[str, Any]:
    """Read and check an image; ``public_key`` is an Ed25519 public key or the path of a
    PEM file holding one. Raises :class:`ImageError` (``KeyFileError`` for a bad key
    file); returns the image object."""
    file = str(path)
    if public_key is not None and not hasattr(public_key, "verify"):
        public_key = load_public_key(public_key)
    try:
        with open(path, "rb") as stream:
            raw = stream.read(MAX_IMAGE_BYTES + 1)
    except OSError as error:
        raise ImageError(file, "unreadable", f"cannot read: {error.strerror}") from None
    if len(raw) > MAX_IMAGE_BYTES:
        raise ImageError(
            file, "over-limit", f"the file is larger than {MAX_IMAGE_BYTES // 2**20} MiB"
        )
    image = _parse(file, raw)
    _check_version(file, image)
    _check_hash(file, image)
    if public_key is not None:
        _check_signature(file, image, public_key)
    _check_schema(file, image)
    _check_consistency(file, image)
    _check_capacity(file, image)
    return image


# --------------------------------------------------------------------------------------
# keel-verify image-check


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "image-check",
        help="check a mission image as a node does before flying it",
        description="Check a mission image written by `keel-verify compile`: format "
        "version, content hash, signature (with --public-key), schema and capacity. "
        "Exit codes: 0 the image may fly, 2 it must be refused (the reason is printed).",
    )
    parser.add_argument("image", help="mission image (JSON, written by keel-verify compile)")
    parser.add_argument("--public-key", metavar="PUB",
                        help="Ed25519 public key (PEM); the image must carry a signature "
                             "that verifies with it")
    parser.set_defaults(func=run)


def _signature_text(image: dict[str, Any], checked: bool) -> str:
    signature = image.get("signature")
    if signature is None:
        return "unsigned"
    if checked:
        return f"signature verified (key id {signature['key_id']})"
    return f"signed with key id {signature['key_id']}, signature not checked (no --public-key)"


def run(args: argparse.Namespace) -> int:
    try:
        image = load_image(args.image, args.public_key)
    except KeyFileError as error:
        print(f"keel-verify: image-check: {error}", file=sys.stderr)
        return EXIT_INVALID
    except ImageError as error:
        print(error, file=sys.stderr)
        return EXIT_INVALID
    content = image["content"]
    print(
        f"{args.image}: mission {image['mission']}: valid image (format {FORMAT_VERSION}, "
        f"proved by keel-verify {image['verifier']}, {len(content['nodes'])} nodes, "
        f"{len(content['tasks'])} tasks, sha256 {image['sha256']}; "
        f"{_signature_text(image, args.public_key is not None)})"
    )
    return EXIT_OK
