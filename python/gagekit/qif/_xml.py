"""lxml access shared by the QIF reader and writer: the one import guard (the ``qif``
extra), the QIF 3.0 namespace, a parser that never touches the network or expands
external entities, and the few typed value readers the model needs.

Why lxml (etree + XPath) and not classes generated from the XSDs (xsdata): the QIF 3.0
schema set is 3.6 MB of XSD defining some 1 700 types; generated bindings are tens of
thousands of lines for the few dozen elements gagekit reads and writes. lxml parses the
1.1 MB CTC 5 model in 0.10 s (the standard library's ElementTree: 0.37 s, best of five on
the shared 2-core machine), reaches any element with XPath, reports the line of a malformed
file, and validates against the official XSDs (``XMLSchema``) in the tests.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

from ..errors import ConfigError, FileFormatError

NS = "http://qifstandards.org/xsd/qif3"
Q = "{%s}" % NS
NSMAP = {"q": NS}


def etree() -> Any:
    """lxml.etree, or one :class:`ConfigError` line naming the extra."""
    try:
        from lxml import etree as _etree
    except ImportError:
        raise ConfigError("QIF import/export needs lxml: pip install 'gagekit[qif]'") from None
    return _etree


def parse(path: Any) -> Any:
    """Parse a QIF file (plain or gzip-compressed) into an lxml tree; a file that is not
    XML is a :class:`FileFormatError` naming the line. Entities are not expanded, no DTD
    or schema is fetched."""
    from .._files import read_bytes

    et = etree()
    data = read_bytes(path, "QIF file")
    if data[:2] == b"\x1f\x8b":
        import gzip
        import zlib

        try:
            data = gzip.decompress(data)
        except (OSError, EOFError, zlib.error) as exc:
            raise FileFormatError(f"{path}: not a readable gzip-compressed QIF file ({exc})") from None
    parser = et.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False, remove_comments=True)
    try:
        return et.fromstring(data, parser).getroottree()
    except et.XMLSyntaxError as exc:
        raise FileFormatError(f"{path}: not a QIF file: the XML is malformed ({exc})") from None
    except ValueError as exc:
        raise FileFormatError(f"{path}: not a QIF file ({exc})") from None


def local(el: Any) -> str:
    """The element's tag without the namespace."""
    tag = el.tag
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def child(el: Any, name: str) -> Optional[Any]:
    return el.find(Q + name)


def children(el: Any, name: str) -> list:
    return el.findall(Q + name)


def text(el: Any, name: str, default: Optional[str] = None) -> Optional[str]:
    c = el.find(Q + name) if el is not None else None
    if c is None or c.text is None:
        return default
    return c.text.strip()


def floats(s: Optional[str], n: int, where: str) -> tuple:
    """``n`` numbers from a QIF list value ('1 0 0')."""
    try:
        vals = tuple(float(x) for x in (s or "").split())
    except ValueError:
        vals = ()
    if len(vals) != n or any(v != v or v in (float("inf"), float("-inf")) for v in vals):
        raise FileFormatError(f"{where}: expected {n} finite number{'s' if n != 1 else ''}, got {s!r}")
    return vals


def number(el: Any, where: str) -> float:
    vals = floats(el.text if el is not None else None, 1, where)
    return vals[0]


def ids(el: Optional[Any]) -> list[str]:
    """The ``Id`` values of an id list (``FeatureNominalIds``...)."""
    if el is None:
        return []
    return [c.text.strip() for c in el.findall(Q + "Id") if c.text]


def sub(parent: Any, name: str, text_value: Optional[str] = None, **attrs: Any) -> Any:
    """Append a QIF element (attributes with a ``None`` value are left out)."""
    et = etree()
    el = et.SubElement(parent, Q + name, {k: str(v) for k, v in attrs.items() if v is not None})
    if text_value is not None:
        el.text = text_value
    return el


def dec(x: Any) -> str:
    """A number as QIF's xs:decimal wants it: positional notation, no exponent, with the
    digits of the shortest repr (so it reads back as the same double, bit for bit)."""
    from decimal import Decimal

    s = format(Decimal(repr(float(x))), "f")
    return "0" if s in ("-0", "-0.0") else s


def vec(v: Any) -> str:
    """A QIF list of numbers ('1 0 0'), each as :func:`dec` writes it."""
    return " ".join(dec(x) for x in v)


def path_name(path: Any) -> str:
    return Path(str(path)).name
