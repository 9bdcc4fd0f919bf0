"""Certificates for Ice over TLS with both sides authenticated: only a holder of the pilot's certificate flies.

    python -m driver certs DIR --host 10.1.1.10 [--host solo.local ...]

makes, in DIR (created 0700):

=================  =====  ===========================================================================
``ca.pem``         0644   the project's CA certificate: both sides trust only it (``IceSSL.CAs``)
``ca-key.pem``     0600   the CA's private key: only for issuing certificates again; keep it here,
                          never on the drone or the pilot's laptop
``server.p12``     0600   the server's key and certificate (SANs: the hosts, 127.0.0.1, localhost)
``client.p12``     0600   the pilot's key and certificate (``IceSSL.CertFile``, Java ``IceSSL.Keystore``)
``truststore.p12`` 0644   the CA certificate as a Java trust store (``IceSSL.Truststore``)
``password.txt``   0600   the PKCS#12 password (``IceSSL.Password``): Java's key stores need one; it
                          protects nothing that the file modes do not
=================  =====  ===========================================================================

PKCS#12 is what IceSSL reads in C++/OpenSSL (and so Python), Java and .NET alike. Keys are EC P-256:
every IceSSL implementation takes them, and the whole folder takes ~45 ms (~0.35 s with RSA 2048 keys).
An existing CA is kept (the server and client certificates are issued again from it, so certificates
already handed out stay valid); ``--new-ca`` replaces it. Files are written to a fresh temporary file
opened with O_NOFOLLOW | O_EXCL, then renamed over the old one: a symlink planted in DIR is never
followed.
"""
from __future__ import annotations

import argparse
import datetime
import ipaddress
import logging
import os
import secrets
import sys
from dataclasses import dataclass

from ..core.files import write_private

log = logging.getLogger(__name__)

CA_CERT, CA_KEY, SERVER, CLIENT, TRUSTSTORE, PASSWORD = (
    "ca.pem", "ca-key.pem", "server.p12", "client.p12", "truststore.p12", "password.txt")
CA_DAYS = 3650
LEAF_DAYS = 825
LOCAL_NAMES = ("127.0.0.1", "localhost")


class CertError(RuntimeError):
    """Certificates cannot be made or read, said in one line."""


@dataclass(frozen=True)
class CertFiles:
    directory: str
    ca_reused: bool
    hosts: tuple[str, ...]

    def path(self, name: str) -> str:
        return os.path.join(self.directory, name)


def _read(path: str) -> bytes:
    """A file's bytes, refusing a symlink (what we wrote is never one)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0))
    with os.fdopen(fd, "rb") as f:
        return f.read()


def read_password(directory: str) -> str:
    """The PKCS#12 password ``certs`` wrote; one clear line if it is not there."""
    path = os.path.join(directory, PASSWORD)
    try:
        return _read(path).decode().strip()
    except OSError as exc:
        raise CertError(f"{path}: {os.strerror(exc.errno).lower() if exc.errno else exc} "
                        f"(make the certificates with: python -m driver certs {directory})") from None


def require(directory: str, *names: str) -> None:
    """Every named file is in ``directory``, or a CertError saying how to make them."""
    for name in names:
        path = os.path.join(directory, name)
        if not os.path.isfile(path):
            raise CertError(f"no {name} in {directory} (make the certificates with: python -m driver certs "
                            f"{directory} --host ADDRESS)")


def _san(host: str):
    from cryptography import x509
    try:
        return x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        return x509.DNSName(host)


def make_certs(directory: str, hosts: list[str] | tuple[str, ...] = (), new_ca: bool = False,
               password: str | None = None) -> CertFiles:
    """The CA (kept if there is one, unless ``new_ca``), the server's and the pilot's certificates."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.hazmat.primitives.serialization import pkcs12
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    directory = os.path.abspath(directory)
    os.makedirs(directory, mode=0o700, exist_ok=True)
    names = list(dict.fromkeys([h.strip() for h in hosts if h.strip()] + list(LOCAL_NAMES)))
    for host in names:
        if host in ("0.0.0.0", "::", "*") or any(c.isspace() for c in host):
            raise CertError(f"--host {host!r}: name the address or host name viewers connect to")
    path = lambda name: os.path.join(directory, name)                      # noqa: E731
    now = datetime.datetime.now(datetime.timezone.utc)
    start = now - datetime.timedelta(minutes=5)                             # a laptop's clock a little behind

    have_ca = os.path.lexists(path(CA_CERT)) or os.path.lexists(path(CA_KEY))
    ca_reused = have_ca and not new_ca
    if ca_reused:
        try:
            ca_cert = x509.load_pem_x509_certificate(_read(path(CA_CERT)))
            ca_key = serialization.load_pem_private_key(_read(path(CA_KEY)), None)
        except (OSError, ValueError) as exc:
            raise CertError(f"{directory} holds a CA that cannot be read ({exc}); --new-ca replaces it "
                            "(certificates it issued stop working)") from None
        if password is None and os.path.isfile(path(PASSWORD)):
            password = read_password(directory)
    else:
        ca_key = ec.generate_private_key(ec.SECP256R1())
        ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "UavViewerPy CA"),
                             x509.NameAttribute(NameOID.ORGANIZATION_NAME, "UavViewerPy")])
        ca_cert = (x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name)
                   .public_key(ca_key.public_key()).serial_number(x509.random_serial_number())
                   .not_valid_before(start).not_valid_after(now + datetime.timedelta(days=CA_DAYS))
                   .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
                   .add_extension(x509.KeyUsage(digital_signature=False, content_commitment=False,
                                                key_encipherment=False, data_encipherment=False,
                                                key_agreement=False, key_cert_sign=True, crl_sign=True,
                                                encipher_only=False, decipher_only=False), critical=True)
                   .add_extension(x509.SubjectKeyIdentifier.from_public_key(ca_key.public_key()), critical=False)
                   .sign(ca_key, hashes.SHA256()))
    password = password if password else secrets.token_urlsafe(18)
    encryption = serialization.BestAvailableEncryption(password.encode())

    def leaf(common_name: str, purposes: list, sans: list[str]):
        key = ec.generate_private_key(ec.SECP256R1())
        builder = (x509.CertificateBuilder()
                   .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, common_name),
                                            x509.NameAttribute(NameOID.ORGANIZATION_NAME, "UavViewerPy")]))
                   .issuer_name(ca_cert.subject).public_key(key.public_key())
                   .serial_number(x509.random_serial_number())
                   .not_valid_before(start).not_valid_after(now + datetime.timedelta(days=LEAF_DAYS))
                   .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
                   .add_extension(x509.KeyUsage(digital_signature=True, content_commitment=False,
                                                key_encipherment=False, data_encipherment=False,
                                                key_agreement=True, key_cert_sign=False, crl_sign=False,
                                                encipher_only=False, decipher_only=False), critical=True)
                   .add_extension(x509.ExtendedKeyUsage(purposes), critical=False)
                   .add_extension(x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()),
                                  critical=False))
        if sans:
            builder = builder.add_extension(x509.SubjectAlternativeName([_san(h) for h in sans]), critical=False)
        return key, builder.sign(ca_key, hashes.SHA256())

    # In a lab (docs/fleet.md) each certificate also serves the other way: a MAVLinkServer calls the IceGrid
    # registry and IceStorm (as a client), and IceStorm calls the viewer back on its telemetry endpoint (the
    # pilot's certificate, without host names, then answers as a server: IceStorm checks the CA, not a name).
    both = [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
    server_key, server_cert = leaf(names[0], both, names)
    client_key, client_cert = leaf("UavViewerPy pilot", both, [])

    if not ca_reused:
        write_private(path(CA_KEY), ca_key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                                  serialization.NoEncryption()), 0o600)
        write_private(path(CA_CERT), ca_cert.public_bytes(serialization.Encoding.PEM), 0o644)
    write_private(path(PASSWORD), (password + "\n").encode(), 0o600)
    write_private(path(SERVER), pkcs12.serialize_key_and_certificates(b"server", server_key, server_cert, [ca_cert],
                                                               encryption), 0o600)
    write_private(path(CLIENT), pkcs12.serialize_key_and_certificates(b"pilot", client_key, client_cert, [ca_cert],
                                                               encryption), 0o600)
    write_private(path(TRUSTSTORE), pkcs12.serialize_java_truststore([pkcs12.PKCS12Certificate(ca_cert, b"ca")],
                                                              encryption), 0o644)
    log.info("certificates in %s for %s (CA %s)", directory, ", ".join(names), "kept" if ca_reused else "new")
    return CertFiles(directory, ca_reused, tuple(names))


def ssl_properties(directory: str, role: str) -> dict[str, str]:
    """IceSSL properties for ``role`` "server" (asks every client for a certificate from our CA) or "client"
    (checks that the server's certificate is from our CA and names the host it dialled)."""
    directory = os.path.abspath(directory)
    own = SERVER if role == "server" else CLIENT
    require(directory, CA_CERT, own, PASSWORD)
    props = {"Ice.Plugin.IceSSL": "IceSSL:createIceSSL", "IceSSL.DefaultDir": directory,
             "IceSSL.CAs": CA_CERT, "IceSSL.CertFile": own, "IceSSL.Password": read_password(directory),
             "IceSSL.VerifyPeer": "2"}
    if role == "client":
        props["IceSSL.CheckCertName"] = "1"
    return props


def main(argv: list[str], prog: str = "python -m driver certs") -> int:
    """``python -m driver certs``: one line per problem, exit 1; the files made, exit 0."""
    p = argparse.ArgumentParser(prog=prog,
                                description="Make the CA, the server's and the pilot's certificates for Ice over "
                                            "TLS (mutual authentication).")
    p.add_argument("directory", metavar="DIR", help="where to write them (created 0700)")
    p.add_argument("--host", action="append", default=[], metavar="NAME_OR_IP",
                   help="an address or name viewers use to reach the server (repeatable); 127.0.0.1 and localhost "
                        "are always added")
    p.add_argument("--new-ca", action="store_true",
                   help="replace an existing CA (every certificate it issued stops working)")
    p.add_argument("--password", help="PKCS#12 password (default: the one in DIR/password.txt, else a random one)")
    opts = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        made = make_certs(opts.directory, opts.host, opts.new_ca, opts.password)
    except (CertError, OSError) as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 1
    print(f"{'kept the CA' if made.ca_reused else 'new CA'} in {made.directory}; server certificate for "
          f"{', '.join(made.hosts)}")
    print(f"  server (the drone):   {CA_CERT} {SERVER} {PASSWORD}   python -m driver --host "
          f"{made.hosts[0]} --certs DIR")
    print(f"  pilot (the laptop):   {CA_CERT} {CLIENT} {PASSWORD}   python main.py --ice-host "
          f"{made.hosts[0]} --ice-certs DIR")
    print(f"  Java clients also:    {TRUSTSTORE}")
    print(f"  keep {CA_KEY} here only (it issues certificates)")
    return 0
