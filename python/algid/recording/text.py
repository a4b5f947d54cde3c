"""Delimited text recordings (``.csv``, ``.tsv``, ``.txt``, each also ``.gz``, ``.bz2``,
``.xz`` or a one-file ``.zip``), parsed chunk by chunk by numpy's C parser (``numpy.loadtxt``;
pandas' would cost its import, 80 MB and 0.3 s, on every command).

The header is the first line that is neither blank nor a ``#`` comment; its delimiter is
the one of tab, ``;``, ``,`` and ``|`` it holds most of (none: blanks). With a delimiter
other than the comma, a data line with a digit, a comma and a digit means a decimal comma.
The file is read in chunks of :data:`CSV_CHUNK_LINES` lines: the memory beyond the data
array (8 bytes a value, only the columns used) is one chunk of text. A line with the wrong
number of fields or a field that is not a number is named by its line number. No line may be
longer than :data:`MAX_LINE_CHARS` nor the header name more than :data:`MAX_COLUMNS` columns
(counted before it is split): a few bytes of ``.bz2`` expand to a line of gigabytes.
"""

from __future__ import annotations

import bz2
import functools
import gzip
import io
import lzma
import re
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..messages import quote
from .columns import Layout, resolve
from .core import RecordingError
from .table import assemble

#: Lines of a text file parsed at a time (the reader's memory beyond the data is about this).
CSV_CHUNK_LINES = 8192
#: Longest line of a text file [characters] and most columns of its header.
MAX_LINE_CHARS = 1 << 26
MAX_COLUMNS = 100_000
TEXT_SUFFIXES = (".csv", ".tsv", ".txt")
COMPRESSIONS = (".gz", ".bz2", ".xz", ".zip")
_DELIMITERS = ("\t", ";", ",", "|")
_DECIMAL_COMMA = re.compile(r"\d,\d")


def _open_zip(path: Path):
    z = zipfile.ZipFile(path)
    files = [info for info in z.infolist() if not info.is_dir()]
    if len(files) != 1:
        z.close()
        raise RecordingError(f"{path.name}: a .zip recording holds one file, this one holds {len(files)}")
    return io.TextIOWrapper(z.open(files[0]), encoding="utf-8-sig")


def open_text(path: Path, compression: str | None):
    """The file as text, decompressed on the fly."""
    if compression == ".zip":
        return _open_zip(path)
    opener = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open}.get(compression)
    if opener is None:
        return open(path, encoding="utf-8-sig")
    return opener(path, "rt", encoding="utf-8-sig")


def _data_lines(fh, source: str):
    """(line number, text) of the lines: blank lines and ``#`` comments skipped, the file read
    line by line, none longer than :data:`MAX_LINE_CHARS`."""
    for lineno, line in enumerate(iter(functools.partial(fh.readline, MAX_LINE_CHARS + 1), ""), start=1):
        if len(line) > MAX_LINE_CHARS:
            raise RecordingError(f"{source}: line {lineno} is longer than {MAX_LINE_CHARS} characters")
        s = line.strip()
        if s and not s.startswith("#"):
            yield lineno, s


def split_header(line: str, source: str = "header") -> tuple[list[str], str | None]:
    """The header's names (quotes dropped) and its delimiter (None: blanks); at most
    :data:`MAX_COLUMNS` of them, counted before the line is split."""
    counts = {d: line.count(d) for d in _DELIMITERS}
    sep = max(counts, key=counts.get)
    width = counts[sep] + 1 if counts[sep] else line.count(" ") + 1  # blanks: at most this many
    if width > MAX_COLUMNS:
        raise RecordingError(f"{source}: the header has {width} columns, more than {MAX_COLUMNS}")
    if counts[sep]:
        return [name.strip().strip('"').strip() for name in line.split(sep)], sep
    names: list[str] = []
    for token in line.split():  # "t [s]  u1 (N)": a unit token belongs to the name before it
        if names and token[0] in "[(":
            names[-1] += " " + token
        else:
            names.append(token)
    return names, None


class _Chunks:
    """Parse data lines chunk by chunk into one (rows, used columns) array."""

    def __init__(self, source: str, names: list[str], sep: str | None, layout: Layout) -> None:
        self.source, self.names, self.sep, self.layout = source, names, sep, layout
        self.decimal = "."
        self.chunks: list[np.ndarray] = []
        self.lines: list[np.ndarray] = []

    def fields(self, text: str) -> list[str]:
        return text.split() if self.sep is None else text.split(self.sep)

    def add(self, texts: list[str], linenos: list[int]) -> None:
        # The first line may hold only integers (t = 0, a signal at rest): any line decides.
        if self.decimal == "." and self.sep not in (None, ",") and any(_DECIMAL_COMMA.search(t) for t in texts):
            self.decimal = ","
        width = len(self.names)
        counts = [len(t.split()) for t in texts] if self.sep is None else [t.count(self.sep) + 1 for t in texts]
        for count, lineno in zip(counts, linenos):
            if count != width:
                raise RecordingError(f"{self.source}: ragged row at line {lineno}: {count} fields, header has {width}")
        rows = [t.replace(",", ".") for t in texts] if self.decimal == "," else texts
        try:
            block = self._parse(rows)
        except ValueError:
            try:  # a logger's empty field is a missing sample: NaN, bridged or refused by the gap rules
                block = self._parse([self._empty_as_nan(t) for t in rows])
            except ValueError:
                self._locate(texts, linenos)
        self.chunks.append(block)
        self.lines.append(np.asarray(linenos, dtype=np.int64))

    def _parse(self, rows: list[str]) -> np.ndarray:
        return np.loadtxt(
            rows, delimiter=self.sep, usecols=self.layout.positions(), ndmin=2, dtype=float, comments=None
        )

    def _empty_as_nan(self, text: str) -> str:
        """A row with its empty fields (``,,``, ``""``) read as NaN."""
        if self.sep is None:
            return text
        return self.sep.join("nan" if f.strip().strip('"') == "" else f for f in text.split(self.sep))

    def _locate(self, texts: list[str], linenos: list[int]) -> None:
        """Raise the one-line error naming the first field that is not a number."""
        for text, lineno in zip(texts, linenos):
            fields = self.fields(text)
            for col in self.layout.positions():
                field = fields[col].strip().strip('"')
                if field == "":  # read as a missing sample (NaN)
                    continue
                try:
                    if "_" in field:  # Python's float reads digit separators; files do not
                        raise ValueError(field)
                    float(field.replace(",", ".") if self.decimal == "," else field)
                except ValueError:
                    raise RecordingError(
                        f"{self.source}: line {lineno}, column {quote(self.names[col])}: "
                        f"cannot parse {quote(field)} as a number"
                    ) from None
        raise RecordingError(f"{self.source}: unreadable data between lines {linenos[0]} and {linenos[-1]}")

    def table(self, header_line: int) -> tuple[np.ndarray, np.ndarray]:
        if not self.chunks:
            raise RecordingError(f"{self.source}: no data rows after the header (line {header_line})")
        data = self.chunks[0] if len(self.chunks) == 1 else np.concatenate(self.chunks)
        self.chunks = []
        return data, np.concatenate(self.lines)


def read_text(path: Path, compression: str | None, columns=None, units=None, dt=None):
    """Read and validate a delimited text recording (see the module docstring)."""
    source = path.name
    try:
        with open_text(path, compression) as fh:
            lines = _data_lines(fh, source)
            first = next(lines, None)
            if first is None:
                raise RecordingError(f"{source}: empty file")
            header_line, header = first
            names, sep = split_header(header, source)
            layout = resolve(names, source, columns, need_time=dt is None)
            chunks = _Chunks(source, names, sep, layout)
            texts: list[str] = []
            linenos: list[int] = []
            for lineno, text in lines:
                texts.append(text)
                linenos.append(lineno)
                if len(texts) == CSV_CHUNK_LINES:
                    chunks.add(texts, linenos)
                    texts, linenos = [], []
            if texts:
                chunks.add(texts, linenos)
    except UnicodeDecodeError:
        raise RecordingError(f"{source}: not a text file (cannot decode as UTF-8)") from None
    except (OSError, EOFError, lzma.LZMAError, zipfile.BadZipFile, zlib.error) as err:
        if compression is None:
            raise
        why = "damaged deflate data" if isinstance(err, zlib.error) else type(err).__name__
        raise RecordingError(f"{source}: not a readable {compression} file ({why})") from None
    data, line_numbers = chunks.table(header_line)
    return assemble(path, source, data, layout, line_numbers, dt=dt, units=units)
