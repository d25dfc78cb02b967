"""``web --serve`` serves the page it wrote and nothing else (docs/web.md, axialdeform/web/serve.py)."""

from __future__ import annotations

import http.client
import os
import threading

import pytest

import axialdeform as ad
from axialdeform.core.errors import AxialDeformError
from axialdeform.web import build_scene, make_server, page_files, write_page


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    home = tmp_path_factory.mktemp("home")
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 4, seed=2)
    page = write_page(home / "page", build_scene(mesh, params))
    folder = page.parent
    # what a hostile page would like to read, beside and outside the page
    (folder / ".ssh").mkdir()
    (folder / ".ssh" / "id_rsa").write_text("PRIVATE KEY")
    (folder / ".env").write_text("TOKEN=1")
    (folder / "notes.txt").write_text("private notes")
    (home / "secret.txt").write_text("outside")
    os.symlink(home, folder / "homelink")
    os.symlink(home / "secret.txt", folder / "scene-link.json")
    server, _ = make_server(folder, 0, files=page_files(folder))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server, folder
    server.shutdown()
    server.server_close()


def get(server, path, host=None, method="GET"):
    port = server.server_address[1]
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    conn.putrequest(method, path, skip_host=True)
    conn.putheader("Host", host if host is not None else f"127.0.0.1:{port}")
    conn.endheaders()
    r = conn.getresponse()
    body = r.read()
    conn.close()
    return r.status, body


def test_the_page_files_are_served(served):
    server, folder = served
    for rel in sorted(page_files(folder)):
        status, body = get(server, "/" + rel)
        assert status == 200, rel
        assert body == (folder / rel).read_bytes(), rel
    status, body = get(server, "/")
    assert status == 200 and body == (folder / "index.html").read_bytes()
    assert get(server, "/", host=f"localhost:{server.server_address[1]}")[0] == 200


@pytest.mark.parametrize("path", ["/.ssh/id_rsa", "/.env", "/%2essh/id_rsa", "/notes.txt", "/homelink/secret.txt",
                                  "/scene-link.json", "/../secret.txt", "/%2e%2e/secret.txt", "/three/",
                                  "/three", "/homelink/", "/index.html%00.txt", "/..%5csecret.txt"])
def test_nothing_else_is_served(served, path):
    server, _ = served
    status, body = get(server, path)
    assert status == 404, (path, status)
    assert b"PRIVATE" not in body and b"outside" not in body and b"private" not in body


@pytest.mark.parametrize("host", ["evil.example:{port}", "evil.example", "127.0.0.1.evil.example:{port}", "",
                                  "127.0.0.1:1"])
def test_a_foreign_host_is_refused(served, host):
    server, _ = served
    status, body = get(server, "/index.html", host=host.format(port=server.server_address[1]))
    assert status == 403 and b"<html" not in body.lower()


def test_only_reads_are_answered(served):
    server, _ = served
    assert get(server, "/index.html", method="POST")[0] == 405
    assert get(server, "/index.html", method="HEAD")[0] == 200


def test_it_listens_on_loopback_only(served):
    server, _ = served
    assert server.server_address[0] == "127.0.0.1"


def test_without_a_list_no_hidden_file_nor_link_out(tmp_path):
    (tmp_path / "site").mkdir()
    (tmp_path / "site" / "index.html").write_text("<p>hi</p>")
    (tmp_path / "site" / ".git").mkdir()
    (tmp_path / "site" / ".git" / "config").write_text("x")
    (tmp_path / "out.txt").write_text("outside")
    os.symlink(tmp_path / "out.txt", tmp_path / "site" / "link.txt")
    server, _ = make_server(tmp_path / "site", 0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        assert get(server, "/")[0] == 200
        assert get(server, "/index.html") == (200, b"<p>hi</p>")
        assert get(server, "/.git/config")[0] == 404
        assert get(server, "/link.txt")[0] == 404
    finally:
        server.shutdown()
        server.server_close()


def test_page_files_of_a_folder_that_is_no_page(tmp_path):
    with pytest.raises(AxialDeformError, match="scene.json"):
        page_files(tmp_path)
    (tmp_path / "scene.json").write_text('{"layers": 3}')
    with pytest.raises(AxialDeformError, match="not a page's scene.json"):
        page_files(tmp_path)


def test_links_into_a_folder_the_caller_names_are_followed(tmp_path):
    (tmp_path / "site").mkdir()
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "mod.js").write_text("export {};")
    (tmp_path / "secret.txt").write_text("outside")
    os.symlink(tmp_path / "lib", tmp_path / "site" / "node_modules")
    os.symlink(tmp_path / "secret.txt", tmp_path / "site" / "s.txt")
    server, _ = make_server(tmp_path / "site", 0, follow=(tmp_path / "lib",))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        assert get(server, "/node_modules/mod.js") == (200, b"export {};")
        assert get(server, "/s.txt")[0] == 404
    finally:
        server.shutdown()
        server.server_close()
