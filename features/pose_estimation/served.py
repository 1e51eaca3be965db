"""Whether a stream URL is a whole file a server gives (it has an end, as a file here has) or
a live stream (a camera's, a playlist's), asked over HTTP(S) as FFmpeg, OpenCV's backend,
asks for the same URL: the same credentials and certificate checks. Its first bytes are
read, and a file's other parts, its index, by range requests where its server answers them
(:class:`ServedFile`); :mod:`features.pose_estimation.containers` reads what they say."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .containers import (
    EBML_START,
    FLV_START,
    UNFINISHED_MP4,
    counted_by_duration,
    cut_short,
    is_mp4,
    mp4_unindexed,
    segment_end,
)


def served_whole(url: str, timeout_s: float | None = None) -> bool:
    """Whether an HTTP(S) URL is a file the server gives whole: it states the file's length
    (a live stream, a camera's, has none: it goes on) and the file is no text (an HLS or DASH
    playlist, whose own length says nothing of the stream's, is); a ``file://`` URL's file
    is (:func:`_local_whole`). False for any other URL and for a server that does not
    answer within ``timeout_s`` (FFmpeg's 30 s when None). Asked
    as FFmpeg asks for the same URL (:func:`_ffmpeg_opener`)."""
    from urllib.parse import urlsplit

    scheme = urlsplit(url).scheme.lower()
    if scheme == "file":
        return _local_whole(url)
    if scheme not in ("http", "https"):
        return False
    answer = _served_start(url, timeout_s, 16)
    if answer is None:
        return False
    status, length, head = answer
    return status == 200 and length is not None and length > 0 and _not_text(head)


def _served_start(
    url: str, timeout_s: float | None, size: int
) -> tuple[int, int | None, bytes] | None:
    """The first ``size`` bytes of the file at an HTTP(S) URL, asked as FFmpeg asks for it
    (:func:`_ffmpeg_opener`), with the answer's status and the length the server states
    (None: none); None where the server cannot be asked or does not answer within
    ``timeout_s`` (FFmpeg's 30 s when None)."""
    import http.client

    try:
        opener, bare = _ffmpeg_opener(url)
        with opener.open(bare, timeout=timeout_s or 30.0) as answer:
            length = (answer.headers.get("Content-Length") or "").strip()
            return answer.status, int(length) if length.isdigit() else None, answer.read(size)
    except (OSError, ValueError, http.client.HTTPException):
        return None


def _not_text(head: bytes) -> bool:
    """Whether a file's first bytes are no text (a playlist's are)."""
    text = head.removeprefix(b"\xef\xbb\xbf")  # a playlist may start with UTF-8's mark
    return bool(text) and not all(32 <= b < 127 or b in b"\t\r\n" for b in text)


def _local_whole(url: str) -> bool:
    """Whether a ``file:`` URL names a file on this machine (it has an end, as a file given
    by its path has) that is no text (a playlist). Its path is what follows ``file:``, as
    FFmpeg reads it (no percent-escapes decoded)."""
    path = Path(url[len("file:") :])
    try:
        with open(path, "rb") as fh:
            return path.is_file() and _not_text(fh.read(16))
    except OSError:
        return False


def _ffmpeg_opener(url: str) -> tuple[Any, str]:
    """A urllib opener that reads an HTTP(S) URL as FFmpeg (OpenCV's backend) reads it, and
    the URL it is to open: credentials in the URL (``http://user:pass@host/...``,
    percent-escapes decoded) are taken out of it (urllib would take ``user:pass@host`` for
    the host) and given when the server asks for them, Basic or Digest, as FFmpeg gives
    them. An HTTPS server's certificate is checked, as the FFmpeg OpenCV ships checks it by
    default (FFmpeg 8: ``tls_verify`` 1; a self-signed server's video does not open), and
    not when the user has turned FFmpeg's check off (``OPENCV_FFMPEG_CAPTURE_OPTIONS``
    holding ``tls_verify;0``): the probe accepts the servers FFmpeg reads from."""
    import ssl
    import urllib.request
    from urllib.parse import unquote, urlsplit, urlunsplit

    parts = urlsplit(url)
    handlers: list[Any] = []
    if parts.username is not None:
        host = parts.netloc.rpartition("@")[2]
        url = urlunsplit(parts._replace(netloc=host))
        passwords = urllib.request.HTTPPasswordMgrWithDefaultRealm()
        passwords.add_password(None, url, unquote(parts.username), unquote(parts.password or ""))
        handlers += [
            urllib.request.HTTPBasicAuthHandler(passwords),
            urllib.request.HTTPDigestAuthHandler(passwords),
        ]
    if not _ffmpeg_verifies_tls():
        unchecked = ssl.create_default_context()
        unchecked.check_hostname = False
        unchecked.verify_mode = ssl.CERT_NONE
        handlers.append(urllib.request.HTTPSHandler(context=unchecked))
    return urllib.request.build_opener(*handlers), url


def _ffmpeg_verifies_tls() -> bool:
    """Whether FFmpeg, opened by OpenCV, checks an HTTPS server's certificate: unless the
    options OpenCV gives it (``OPENCV_FFMPEG_CAPTURE_OPTIONS``, ``key;value`` pairs joined
    by ``|``) set ``tls_verify`` to 0."""
    options = os.environ.get("OPENCV_FFMPEG_CAPTURE_OPTIONS", "")
    for pair in options.split("|"):
        key, _, value = pair.partition(";")
        if key.strip() == "tls_verify":
            return value.strip() not in ("0", "false")
    return True


def served_whole_by_duration(url: str, timeout_s: float | None = None) -> bool:
    """Whether an HTTP(S) URL is a file whose frame count OpenCV takes from its duration
    (:func:`.containers.counted_by_duration`) and that its server gives whole, so that
    fewer frames than that count are no sign of a cut: an MPEG-TS file (its duration comes from the
    packets there are), an FLV file (not cut short: :func:`served_cut`, asked first), or a
    Matroska/WebM file whose segment states its size and ends
    within the length the server states (a file cut short on the server states more).
    Its first bytes only are read."""
    answer = _served_start(url, timeout_s, 4096)
    if answer is None:
        return False
    _status, length, head = answer
    if not head.startswith(EBML_START):
        return counted_by_duration(head)  # MPEG-TS, or no file counted so
    if length is None:
        return False
    end = segment_end(head)
    return end is not None and end <= length


def served_cut(
    url: str, timeout_s: float | None = None, alive: Callable[[], None] | None = None
) -> str | None:
    """Why an MP4/MOV, Matroska/WebM or FLV file an HTTP(S) server gives whole is cut short
    or unfinished, in one line (:func:`.containers.cut_short`: it ends inside a box, an
    element or a tag, or its frames have no index, as a file here is refused for; an MP4 cut
    inside its last frame decodes as whole, one cut before its index, at its end, or still
    being recorded, does not open), or None: not cut, no such file, or not to be asked (no
    answer within ``timeout_s``: FFmpeg's 30 s when None). A browser's WebM without a
    duration states no frame count: its frames before the cut were watched as the whole
    file. The file is read once more from its start to its end, walked as it comes (no copy
    kept); a server that sends less than the length it states has cut it too. A server that
    states no length (sending a file as it is written) is asked only whether an MP4/MOV's
    frames have an index (:func:`.containers.mp4_unindexed`, within the stream's start).
    ``alive``: called as each part of the file comes (a long file read again is no stall)."""
    import http.client

    try:
        opener, bare = _ffmpeg_opener(url)
        with opener.open(bare, timeout=timeout_s or 30.0) as answer:
            length = (answer.headers.get("Content-Length") or "").strip()
            # an MP4/MOV file's first box's size and name, and a HEIF photo's brand
            head = answer.read(16)
            if answer.status != 200:
                return None
            if not length.isdigit():  # no end to walk to: an MP4 being recorded, sent so?
                unsized = _Onward(answer, head, 0, alive)
                unindexed = is_mp4(head) and mp4_unindexed(unsized, None)
                return UNFINISHED_MP4.format("the served file's") if unindexed else None
            if not (head.startswith((EBML_START, FLV_START)) or is_mp4(head)):
                return None
            body = _Onward(answer, head, int(length), alive)
            cut = cut_short(body, int(length), head, "the served file")
            body.seek(int(length))  # to its end: did all of it come?
            if body.got < int(length):
                return (
                    f"truncated: the server sent {body.got:,} of the {int(length):,} bytes"
                    " it stated"
                )
            return cut
    except (OSError, ValueError, http.client.HTTPException):
        return None


def served_refusal(url: str, timeout_s: float | None = None) -> str | None:
    """Why the server of an HTTP(S) URL that OpenCV could not open gives no video, in a few
    words, as it answers FFmpeg's request for the same URL (:func:`_ffmpeg_opener`): an
    error status ("the server answered HTTP 404 (Not Found)"), no server at its address
    ("connection refused") or no such host, a certificate FFmpeg would not trust, or a web
    page or plain text where a video was asked for (an HLS playlist is no such text: "the
    server gives text/html, not a video"); None
    when it is none of these or gives no answer within ``timeout_s`` (FFmpeg's 30 s when
    None)."""
    import http.client
    import socket
    import ssl
    import urllib.error
    from http import HTTPStatus
    from urllib.parse import urlsplit

    host = urlsplit(url).netloc.rpartition("@")[2]
    try:
        opener, bare = _ffmpeg_opener(url)
        with opener.open(bare, timeout=timeout_s or 30.0) as answer:
            kind = (answer.headers.get("Content-Type") or "").partition(";")[0].strip().lower()
            head = answer.read(16)
    except urllib.error.HTTPError as exc:
        try:
            phrase = HTTPStatus(exc.code).phrase
        except ValueError:  # a status HTTP does not define: the server's own words
            phrase = str(exc.reason)
        return f"the server answered HTTP {exc.code} ({phrase})"
    except urllib.error.URLError as exc:
        reason = exc.reason
        if isinstance(reason, ConnectionRefusedError):
            return f"no server answers at {host} (connection refused)"
        if isinstance(reason, socket.gaierror):
            return f"no such host: {urlsplit(url).hostname}"
        if isinstance(reason, ssl.SSLCertVerificationError):
            return f"the server's certificate is not trusted ({reason.verify_message})"
        return None
    except (OSError, ValueError, http.client.HTTPException):
        return None
    if kind in ("text/html", "text/plain") and not head.lstrip().startswith(b"#EXTM3U"):
        return f"the server gives {kind}, not a video"
    return None


SERVED_START = 1 << 16
"""How much of a served file's start (bytes) :func:`served_file` asks for: an MP4/MOV
file's boxes before its frames and, written for streaming ("fast start"), its index; a
HEIF photo's meta box."""
SERVED_INDEX_LIMIT = 8 << 20
"""The most a :class:`ServedFile` reads of a served file (bytes) past its start, in
:data:`SERVED_READS` range requests at most: an MP4/MOV file's index at its end (an hour of
a phone's recording at 60 fps indexes its frames in some megabytes). A file whose index
takes more is opened unchecked, as before, not read for minutes."""
SERVED_READS = 8
"""The most range requests a :class:`ServedFile` makes (each box before an MP4's index,
past its start, is one)."""


class Unread(Exception):
    """A :class:`ServedFile`'s bytes that cannot be read: the server does not answer range
    requests, or more than :data:`SERVED_INDEX_LIMIT` would be read."""


class ServedFile:
    """A file an HTTP(S) server gives whole (``length`` bytes, its first bytes ``start``),
    read as a file here is (``seek``, ``read``, ``tell``) for what its bytes say
    (:mod:`.containers`): its start as it came, any other part by a range request
    (``Range: bytes=N-M``, as FFmpeg asks for the part it seeks to) of at least
    :data:`SERVED_START` bytes, within :data:`SERVED_INDEX_LIMIT` and :data:`SERVED_READS`;
    :class:`Unread` raised for a part it cannot read (a server that does not answer range
    requests gives the start alone)."""

    def __init__(
        self, url: str, length: int, start: bytes, ranged: bool, timeout_s: float | None
    ) -> None:
        self.url, self.length, self.start, self.ranged = url, length, start, ranged
        self.timeout_s = timeout_s
        self.parts: list[tuple[int, bytes]] = [(0, start)]
        self.at, self.spent, self.reads = 0, 0, 0

    def tell(self) -> int:
        return self.at

    def seek(self, to: int) -> None:
        self.at = to

    def read(self, n: int) -> bytes:
        end = min(self.at + n, self.length)
        if end <= self.at:
            return b""
        part = next(
            (p for p in self.parts if p[0] <= self.at and end <= p[0] + len(p[1])), None
        ) or self._fetched(self.at, end)
        out = part[1][self.at - part[0] : end - part[0]]
        self.at = end
        return out

    def _fetched(self, first: int, end: int) -> tuple[int, bytes]:
        """The bytes from ``first`` to at least ``end``, asked of the server."""
        end = min(max(end, first + SERVED_START), self.length)
        self.reads += 1
        self.spent += end - first
        if not self.ranged or self.reads > SERVED_READS or self.spent > SERVED_INDEX_LIMIT:
            raise Unread(f"bytes {first}-{end - 1}")
        answer = _served_part(self.url, self.timeout_s, first, end)
        if answer is None or answer[0] != 206 or len(answer[2]) != end - first:
            raise Unread(f"bytes {first}-{end - 1}")
        self.parts.append((first, answer[2]))
        return self.parts[-1]


def served_file(url: str, timeout_s: float | None = None) -> ServedFile | None:
    """The file at an HTTP(S) URL as a :class:`ServedFile` to read: its first
    :data:`SERVED_START` bytes asked for by a range request, as FFmpeg asks (a server that
    answers it, 206, states the file's length in its Content-Range; one that does not gives
    the whole file, 200, and its length, of which the start alone is read). None when it is
    no file of a length stated (a live stream, an error, no answer within ``timeout_s``:
    FFmpeg's 30 s when None)."""
    answer = _served_part(url, timeout_s, 0, SERVED_START)
    if answer is None:
        return None
    status, length, start = answer
    if status not in (200, 206) or length is None or length <= 0:
        return None
    return ServedFile(url, length, start, status == 206, timeout_s)


def _served_part(
    url: str, timeout_s: float | None, first: int, end: int
) -> tuple[int, int | None, bytes] | None:
    """The bytes ``first`` to ``end`` (not included) of the file at an HTTP(S) URL asked for
    by a range request, as FFmpeg asks (:func:`_ffmpeg_opener`), with the answer's status
    (206: the part; 200: the server gives the whole file, of which the first ``end - first``
    bytes are read) and the whole file's length (its Content-Range's, or Content-Length's
    for a 200; None: none stated, and nothing read: a live stream may send its bytes
    slowly); None where the server cannot be asked or does not answer within ``timeout_s``
    (FFmpeg's 30 s when None)."""
    import http.client
    import urllib.request

    try:
        opener, bare = _ffmpeg_opener(url)
        asked = urllib.request.Request(bare, headers={"Range": f"bytes={first}-{end - 1}"})
        with opener.open(asked, timeout=timeout_s or 30.0) as answer:
            if answer.status == 206:  # "bytes FIRST-LAST/LENGTH"
                stated = (answer.headers.get("Content-Range") or "").removeprefix("bytes ")
                span, _, whole = stated.partition("/")
                if span.partition("-")[0].strip() != str(first):
                    return None  # not the part asked for
            else:
                whole = (answer.headers.get("Content-Length") or "").strip()
            if not whole.isdigit():
                return answer.status, None, b""
            return answer.status, int(whole), answer.read(end - first)
    except (OSError, ValueError, http.client.HTTPException):
        return None


class _Onward:
    """An HTTP answer's body (its first bytes ``head`` already read, ``length`` stated) read
    as a file that is only read onward: ``seek`` ahead reads and drops the bytes between;
    ``got``: how many bytes came."""

    def __init__(
        self, answer: Any, head: bytes, length: int, alive: Callable[[], None] | None
    ) -> None:
        self.answer, self.buffer, self.at = answer, head, 0
        self.got, self.length, self.ended = len(head), length, False
        self.alive = alive

    def tell(self) -> int:
        return self.at

    def read(self, n: int) -> bytes:
        out = self.buffer[:n]
        self.buffer = self.buffer[n:]
        while len(out) < n:
            more = b"" if self.ended else self.answer.read(min(n - len(out), 1 << 16))
            if not more:
                self.ended = True
                break
            self.got += len(more)
            out += more
            if self.alive is not None:
                self.alive()
        self.at += len(out)
        return out

    def seek(self, to: int) -> None:
        while self.at < to and not self.ended:
            self.read(min(to - self.at, 1 << 16))
