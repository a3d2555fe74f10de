"""An uploaded image, from the request to a checked file on disk.

``receive_image`` streams one multipart/form-data request body into a file, a chunk at a time,
and stops as soon as the file passes its size cap: an upload is never held in memory whole, and a
huge one costs at most the cap in disk before it is refused. The name the browser sent is kept as
text for the page (never used as a path: the file on disk is named by the server).

``check_image`` then reads the file as ``predict`` will, under the project's image rules: its
size from the header before any pixel is decoded (``MAX_IMAGE_PIXELS``, the processor's
``MAX_ASPECT_RATIO``, ``MIN_IMAGE_SIDE``), then the whole decode, so a truncated or corrupt image
is refused at the upload instead of failing later in the queue.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from PIL import Image, UnidentifiedImageError
from python_multipart.multipart import MultipartParser, parse_options_header

from jax3dc.processing.processor import MAX_ASPECT_RATIO, MIN_IMAGE_SIDE

FIELD = "image"  # the form field of the image file
MAX_NAME_CHARS = 200  # of the file name kept for the page
MAX_FIELD_BYTES = 4096  # of a form field that is not the image (ignored, but read)


class UploadError(Exception):
    """An upload refused: ``status`` is the HTTP status of the reply, the message one line for a person."""

    def __init__(self, status: int, message: str):
        self.status = status
        self.message = message
        super().__init__(message)


@dataclass(frozen=True)
class Upload:
    """An image file received: where the server wrote it, and the name the browser gave it (text only)."""

    path: Path
    filename: str


def shown_name(raw: bytes) -> str:
    """The uploaded file's name as text for the page and the JSON replies: decoded leniently, its
    control characters dropped and cut to MAX_NAME_CHARS. It may still hold ``../`` or markup:
    the page escapes it, and folders are named by ``jax3dc.predict.batch.folder_name``."""
    text = raw.decode("utf-8", errors="replace")
    return "".join(c for c in text if c.isprintable())[:MAX_NAME_CHARS] or "image"


class _Receiver:
    """The multipart parser's callbacks: the image field's bytes into ``target``, up to ``cap``."""

    def __init__(self, target: BinaryIO, cap: int):
        self.target, self.cap = target, cap
        self.header_name, self.header_value, self.disposition = b"", b"", b""
        self.in_image = False
        self.filename: str | None = None
        self.written = 0
        self.field_bytes = 0
        self.ended = False

    def on_part_begin(self) -> None:
        self.disposition, self.in_image, self.field_bytes = b"", False, 0

    def on_header_field(self, data: bytes, start: int, end: int) -> None:
        self.header_name += data[start:end]

    def on_header_value(self, data: bytes, start: int, end: int) -> None:
        self.header_value += data[start:end]

    def on_header_end(self) -> None:
        if self.header_name.strip().lower() == b"content-disposition":
            self.disposition = self.header_value
        self.header_name, self.header_value = b"", b""

    def on_headers_finished(self) -> None:
        _kind, options = parse_options_header(self.disposition)
        if options.get(b"name") == FIELD.encode() and b"filename" in options:
            if self.filename is not None:
                raise UploadError(400, f"one image per request: the form has two '{FIELD}' files")
            self.filename = shown_name(options[b"filename"])
            self.in_image = True

    def on_part_data(self, data: bytes, start: int, end: int) -> None:
        size = end - start
        if not self.in_image:
            self.field_bytes += size
            if self.field_bytes > MAX_FIELD_BYTES:
                raise UploadError(400, f"a form field other than '{FIELD}' is over {MAX_FIELD_BYTES} bytes")
            return
        self.written += size
        if self.written > self.cap:
            raise UploadError(413, f"the image is over the upload cap of {self.cap / 1e6:g} MB")
        self.target.write(data[start:end])

    def on_part_end(self) -> None:
        self.in_image = False

    def on_end(self) -> None:
        self.ended = True

    def callbacks(self) -> dict:
        return {name: getattr(self, name) for name in (
            "on_part_begin", "on_header_field", "on_header_value", "on_header_end", "on_headers_finished",
            "on_part_data", "on_part_end", "on_end")}


async def receive_image(content_type: str | None, body: AsyncIterator[bytes], path: Path, cap: int) -> Upload:
    """Streams the ``image`` file of a multipart/form-data ``body`` into ``path`` (created), at
    most ``cap`` bytes; UploadError for a body that is not such a form, has no image, is cut short
    (the form's closing boundary never came) or passes the cap. ``path`` is removed on an error."""
    kind, options = parse_options_header(content_type or "")
    if kind != b"multipart/form-data" or not options.get(b"boundary"):
        raise UploadError(415, f"send the image as multipart/form-data with the file in the field '{FIELD}'")
    try:
        with path.open("wb") as target:
            receiver = _Receiver(target, cap)
            parser = MultipartParser(options[b"boundary"], receiver.callbacks())
            async for chunk in body:
                parser.write(chunk)
            parser.finalize()
        if receiver.filename is None:
            raise UploadError(400, f"the form has no file in the field '{FIELD}'")
        if not receiver.ended:
            raise UploadError(400, "the upload was cut short: the form ended before its closing boundary")
        if receiver.written == 0:
            raise UploadError(400, "the uploaded file is empty")
        return Upload(path, receiver.filename)
    except UploadError:
        path.unlink(missing_ok=True)
        raise
    except Exception as e:  # the parser's own errors (a malformed form), a client gone mid-upload
        path.unlink(missing_ok=True)
        raise UploadError(400, f"the upload could not be read as a form: {type(e).__name__}") from None


def check_image(path: Path, max_pixels: int) -> tuple[int, int]:
    """(width, height) of the image file at ``path`` when ``predict`` would read it; else
    UploadError 400 naming why. The size rules are checked on the header alone; only an image that
    passes them is decoded (to refuse truncated or corrupt data now)."""
    pil_cap = Image.MAX_IMAGE_PIXELS
    try:
        Image.MAX_IMAGE_PIXELS = None  # the cap below, with its own message, applies instead of PIL's
        try:
            image = Image.open(path)
        finally:
            Image.MAX_IMAGE_PIXELS = pil_cap
        with image:
            width, height = image.size
            if width * height > max_pixels:
                raise UploadError(400, f"the image is {width} x {height} pixels; the cap is {max_pixels} pixels")
            if min(width, height) < MIN_IMAGE_SIDE:
                raise UploadError(400, f"the image is {width} x {height} pixels; a side must be at least "
                                       f"{MIN_IMAGE_SIDE} px")
            if max(width, height) / min(width, height) > MAX_ASPECT_RATIO:
                raise UploadError(400, f"the image is {width} x {height} pixels; one side may be at most "
                                       f"{MAX_ASPECT_RATIO} times the other")
            image.load()
            return width, height
    except UnidentifiedImageError:
        raise UploadError(400, "not an image file (format not recognised)") from None
    except (OSError, SyntaxError, ValueError, Image.DecompressionBombError) as e:
        raise UploadError(400, f"corrupt or truncated image data ({e})") from None
