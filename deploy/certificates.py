"""TLS certificates for a run's router: a certificate authority made for the run and the
router's certificate signed by it (ECDSA P-256), written as PEM files.

Zenoh clients verify the router's certificate against the authority and its name against the
endpoint's host, so the certificate names ``localhost``, ``127.0.0.1`` and the hosts given (the
names other hosts use to reach the router).  Across hosts (docs/hosts.md) every host's router
has a certificate of its own from the one authority, named ``router-<host>``: a router that
links to the hub knows the hub by its certificate's name (the access rules' subject).  Each
account's client configuration carries the authority inline (``deploy.access``).
"""

from __future__ import annotations

import datetime as dt
import ipaddress
from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import NameOID

from deploy.access import TlsFiles

VALID_DAYS = 30


@dataclass(frozen=True)
class Authority:
    """A run's certificate authority: its key (kept in memory), name and PEM file."""

    key: ec.EllipticCurvePrivateKey
    name: x509.Name
    pem: Path


def write_authority(directory: Path) -> Authority:
    """Make the run's certificate authority, its certificate written to
    ``directory/authority.pem``."""
    directory.mkdir(parents=True, exist_ok=True, mode=0o700)
    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "inspection run authority")])
    ca = _certificate(name, name, key.public_key(), key, is_ca=True, names=())
    pem = directory / "authority.pem"
    pem.write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    return Authority(key, name, pem)


def write_certificate(authority: Authority, directory: Path, stem: str, common_name: str,
                      names: tuple[str, ...]) -> TlsFiles:
    """A router's certificate (``<stem>.pem``, named ``common_name``, valid for ``names``: host
    names or IP addresses) and key (``<stem>.key``, owner only), signed by ``authority``."""
    key = ec.generate_private_key(ec.SECP256R1())
    subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, common_name)])
    cert = _certificate(subject, authority.name, key.public_key(), authority.key, is_ca=False,
                        names=names)
    files = TlsFiles(directory / f"{stem}.pem", directory / f"{stem}.key", authority.pem)
    files.certificate.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    files.private_key.touch(mode=0o600)
    files.private_key.write_bytes(key.private_bytes(
        serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption()))
    return files


def write_tls_files(directory: Path, hosts: tuple[str, ...] = ()) -> TlsFiles:
    """Make the run's authority and the router's certificate for ``localhost``, ``127.0.0.1`` and
    ``hosts`` (names or IP addresses) in ``directory``; keys readable by the owner only."""
    return write_certificate(write_authority(directory), directory, "router", "localhost",
                             ("localhost", "127.0.0.1", *hosts))


def _certificate(subject: x509.Name, issuer: x509.Name, public_key: ec.EllipticCurvePublicKey,
                 signer: ec.EllipticCurvePrivateKey, is_ca: bool,
                 names: tuple[str, ...]) -> x509.Certificate:
    now = dt.datetime.now(dt.UTC)
    builder = (x509.CertificateBuilder().subject_name(subject).issuer_name(issuer)
               .public_key(public_key).serial_number(x509.random_serial_number())
               .not_valid_before(now - dt.timedelta(minutes=5))
               .not_valid_after(now + dt.timedelta(days=VALID_DAYS))
               .add_extension(x509.BasicConstraints(ca=is_ca, path_length=None), critical=True))
    if names:
        builder = builder.add_extension(
            x509.SubjectAlternativeName([_general_name(n) for n in names]), critical=False)
    return builder.sign(signer, hashes.SHA256())


def _general_name(name: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(name))
    except ValueError:
        return x509.DNSName(name)
