"""The model client over HTTPS: the TLS handshake (rustls with the `ring` provider), the
server's certificate checked against the roots the environment trusts
(`SSL_CERT_FILE`), and a refusal when no trusted authority signed it. The server is
the tests' real model behind Python's own TLS (OpenSSL), with certificates that the
`openssl` command makes for the test."""

from __future__ import annotations

import select
import socket
import ssl
import subprocess
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit

import pytest

import coherent
from conftest import MODEL_KEY


def _openssl(*args: str | Path) -> None:
    subprocess.run(["openssl", *map(str, args)], check=True, capture_output=True)


def _authority(folder: Path, name: str) -> tuple[Path, Path]:
    """A self-signed certificate authority: its certificate and key."""
    cert, key = folder / f"{name}.pem", folder / f"{name}.key"
    _openssl(
        "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256", "-nodes", "-days", "2",
        "-subj", f"/CN={name}", "-keyout", key, "-out", cert,
    )  # fmt: skip
    return cert, key


@dataclass(frozen=True)
class _Certificates:
    ca: Path
    """The authority that signed the server's certificate."""
    other_ca: Path
    """An authority that did not."""
    server_cert: Path
    server_key: Path


@pytest.fixture(scope="module")
def certificates(tmp_path_factory: pytest.TempPathFactory) -> _Certificates:
    folder = tmp_path_factory.mktemp("tls")
    ca, ca_key = _authority(folder, "coherent-test-ca")
    other_ca, _ = _authority(folder, "coherent-other-ca")
    key, request, cert = folder / "server.key", folder / "server.csr", folder / "server.pem"
    _openssl(
        "req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256", "-nodes",
        "-subj", "/CN=127.0.0.1", "-keyout", key, "-out", request,
    )  # fmt: skip
    extensions = folder / "server.ext"
    extensions.write_text("subjectAltName=IP:127.0.0.1\nbasicConstraints=CA:FALSE\nextendedKeyUsage=serverAuth\n")
    _openssl(
        "x509", "-req", "-in", request, "-CA", ca, "-CAkey", ca_key, "-CAcreateserial", "-days", "2",
        "-extfile", extensions, "-out", cert,
    )  # fmt: skip
    return _Certificates(ca=ca, other_ca=other_ca, server_cert=cert, server_key=key)


class _TlsFront:
    """TLS in front of a plain HTTP server: each connection's handshake is Python's
    (OpenSSL), and the bytes then pass both ways, on one thread per connection (an
    SSL socket must not be read and written from two threads at once)."""

    def __init__(self, upstream: tuple[str, int], certificates: _Certificates) -> None:
        self.upstream = upstream
        self.context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        self.context.load_cert_chain(certificates.server_cert, certificates.server_key)
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.stopped = threading.Event()
        self.threads = [threading.Thread(target=self._accept)]
        self.threads[0].start()

    def _accept(self) -> None:
        while not self.stopped.is_set():
            if not select.select([self.listener], [], [], 0.1)[0]:
                continue
            client, _ = self.listener.accept()
            thread = threading.Thread(target=self._serve, args=(client,))
            self.threads.append(thread)
            thread.start()

    def _serve(self, client: socket.socket) -> None:
        with client:
            try:
                tls = self.context.wrap_socket(client, server_side=True)
            except (ssl.SSLError, OSError):
                return  # the client refused the handshake
            with tls, socket.create_connection(self.upstream) as upstream:
                self._pass_bytes(tls, upstream)

    def _pass_bytes(self, tls: ssl.SSLSocket, upstream: socket.socket) -> None:
        while not self.stopped.is_set():
            # Bytes already decrypted and buffered do not make the socket readable.
            readable = [tls] if tls.pending() else select.select([tls, upstream], [], [], 0.1)[0]
            for source in readable:
                sink = upstream if source is tls else tls
                try:
                    data = source.recv(65536)
                    if not data:
                        return
                    sink.sendall(data)
                except (ssl.SSLError, OSError):
                    return

    def stop(self) -> None:
        self.stopped.set()
        for thread in self.threads:
            thread.join()
        self.listener.close()


@pytest.fixture(scope="module")
def https_model(local_model: str, certificates: _Certificates) -> Iterator[str]:
    """The tests' model at an https:// base URL."""
    address = urlsplit(local_model)
    front = _TlsFront((address.hostname or "127.0.0.1", address.port or 80), certificates)
    yield f"https://127.0.0.1:{front.port}/v1"
    front.stop()


def _trusting(monkeypatch: pytest.MonkeyPatch, ca: Path) -> None:
    # The client reads the roots it trusts when it is made: these and no others.
    monkeypatch.setenv("SSL_CERT_FILE", str(ca))
    monkeypatch.delenv("SSL_CERT_DIR", raising=False)


def test_a_model_behind_https_answers_once_its_authority_is_trusted(
    https_model: str,
    certificates: _Certificates,
    env0_tasks: list[coherent.Task],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    _trusting(monkeypatch, certificates.ca)
    llm = coherent.LLM(base_url=https_model, model="smollm2-135m", api_key=MODEL_KEY, max_retries=0)
    episode = coherent.run(env0_tasks[2], llm=llm, max_steps=1, out=tmp_path)
    assert episode.status == "failure" and episode.steps == 1
    assert episode.llm_calls >= 1 and episode.completion_tokens > 0
    assert episode.backend["base_url"] == https_model


def test_a_server_certificate_no_trusted_authority_signed_is_refused(
    https_model: str,
    certificates: _Certificates,
    env0_tasks: list[coherent.Task],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    _trusting(monkeypatch, certificates.other_ca)
    llm = coherent.LLM(base_url=https_model, model="smollm2-135m", api_key=MODEL_KEY, max_retries=0)
    with pytest.raises(coherent.BackendError, match="certificate") as info:
        coherent.run(env0_tasks[2], llm=llm, max_steps=1, out=tmp_path)
    episode = info.value.episode
    assert episode.status == "backend_error" and episode.completion_tokens == 0
