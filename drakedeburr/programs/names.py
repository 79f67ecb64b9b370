"""Names and remarks written into robot programs: nothing from the inputs becomes code.

Every text that reaches a program comes through here. A *name* (RAPID module, KRL DEF/DEFDAT,
FANUC /PROG, data names) must be an identifier by the controller language's rules, or it is
refused (:class:`ProgramNameError`, an :class:`~drakedeburr.errors.InputError`: exit 2, one line
naming the item); :func:`clean_identifier` turns a *derived* name (from a hub folder or a CL
file name) into one deterministically. A *remark* (header lines, move comments: hub and
scenario names, CL tool path names, tool titles, file names) goes through
:func:`comment_text`, which leaves one printable ASCII line that cannot end the comment or
open code.

Identifier rules (a conservative subset of each language, so one name works everywhere it is
written):

* ABB RAPID: a letter, then letters, digits or '_', at most 32 characters; not a reserved word;
  upper and lower case are the same identifier. Technical reference manual RAPID kernel
  (3HAC050946-001), "Identifiers" and "Reserved words"; the reserved-word list is the one of
  BossyMr/intellij-rapid ``src/main/java/com/bossymr/rapid/language/lexer/RapidLexer.java``
  @dc6c2d0 (``KEYWORDS``, which also rejects names over 32 characters).
* KUKA KRL: at most 24 characters, letters A-Z, digits, '_' and '$', not starting with a digit,
  not a keyword (KUKA KSS 8.x "Quickguide KRL-Syntax", Variables and declarations: "Names in
  KRL"). '$' is left out here: system variables start with it. Keywords: the statement,
  motion, type and operator keywords of KnoP-01/krl-for-vim ``syntax/krl.vim`` @002cb11.
  KRL ignores case.
* FANUC TP (LS): the program name is the file name: a letter, then letters, digits or '_', at
  most 36 characters (R-30iA and later; docs/post.md); written in upper case.

Each language also refuses the names the writers declare themselves (RAPID ``main``,
``p<n>``, speed and zone data; KRL ``XP<n>``, ``BAS``), so a program cannot be named like one
of its own data.

Policy (docs/post.md "Names"): a name the user typed (``--name``, the ``-o`` file name of a
KRL or LS program) that is not an identifier is refused; a name derived from a hub folder or
a CL file is cleaned like CAM posts do (RoboDK's ``get_safe_name``, Autodesk's Fanuc LS post):
every run of other characters becomes '_', a leading digit gets a ``P_`` prefix, the name is
cut to the length limit and a reserved word gets ``_1`` appended.
"""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass

from drakedeburr.errors import InputError

__all__ = ["IdentifierRule", "RULES", "ProgramNameError", "identifier_problem",
           "check_identifier", "clean_identifier", "comment_text", "LANGUAGES"]

LANGUAGES = ("rapid", "krl", "ls")

_RAPID_RESERVED = frozenset("""
ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF
ENDMODULE ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO IF
INOUT LOCAL MOD MODULE NOSTEPIN NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY RETURN
STEP SYSMODULE TASK TEST THEN TO TRAP TRUE TRYNEXT UNDO VAR VIEWONLY WHILE WITH XOR
""".split())
_KRL_RESERVED = frozenset("""
DEF END DEFDAT ENDDAT DEFFCT ENDFCT DECL GLOBAL CONST STRUC ENUM PUBLIC
IF THEN ELSE ENDIF SWITCH CASE DEFAULT ENDSWITCH FOR TO STEP ENDFOR WHILE ENDWHILE REPEAT UNTIL
LOOP ENDLOOP EXIT GOTO RETURN RESUME HALT CONTINUE INTERRUPT WAIT SEC ON OFF ENABLE DISABLE
STOP TRIGGER WITH WHEN DISTANCE PATH ONSTART DELAY DO PRIO IMPORT IS MINIMUM MAXIMUM CONFIRM
ON_ERROR_PROCEED ANIN ANOUT DIGIN
AND OR EXOR NOT DIV MOD B_AND B_OR B_EXOR B_NOT TRUE FALSE
BOOL CHAR REAL INT EXT EXTFCT EXTFCTP EXTP SIGNAL CHANNEL
FRAME E6POS POS E6AXIS AXIS FDAT LDAT PDAT LOAD INERTIA
PTP LIN CIRC SPL SPTP SLIN SCIRC PTP_REL LIN_REL CIRC_REL SPTP_REL SLIN_REL SCIRC_REL
ASYPTP ASYCONT ASYSTOP ASYCANCEL BRAKE BRAKE_F CA C_PTP C_DIS C_VEL C_ORI C_SPL SPLINE ENDSPLINE
""".split())
# the names the writers declare or call in every program of the language
_RAPID_OWN = re.compile(r"(?i)main|fine|tool0|wobj0|load0|p\d+|v\d+|z\d+|vdd\d+_\d+|zdd\d+_\d+"
                        r"|vmax")
_KRL_OWN = re.compile(r"(?i)XP\d+|BAS|INI")


@dataclass(frozen=True)
class IdentifierRule:
    """One language's identifier rule.

    Attributes:
        language: "rapid", "krl" or "ls".
        max_length: most characters.
        reserved: reserved words (upper case; compared ignoring case).
        own: names the writers use themselves (full match, ignoring case), or None.
        text: the rule in words (for messages).
    """

    language: str
    max_length: int
    reserved: frozenset[str]
    own: re.Pattern | None
    text: str

    def pattern(self) -> re.Pattern:
        return re.compile(rf"[A-Za-z][A-Za-z0-9_]{{0,{self.max_length - 1}}}")


RULES = {
    "rapid": IdentifierRule("rapid", 32, _RAPID_RESERVED, _RAPID_OWN,
                            "a letter, then letters, digits, '_', at most 32 characters, not "
                            "a RAPID reserved word"),
    "krl": IdentifierRule("krl", 24, _KRL_RESERVED, _KRL_OWN,
                          "a letter, then letters, digits, '_', at most 24 characters, not a "
                          "KRL keyword"),
    "ls": IdentifierRule("ls", 36, frozenset(), None,
                         "a letter, then letters, digits, '_', at most 36 characters"),
}


class ProgramNameError(InputError):
    """A name that would be written into a program as code is not an identifier of the
    language; the message names the item, the name and the rule."""


def _rule(language: str) -> IdentifierRule:
    try:
        return RULES[language]
    except KeyError:
        raise InputError(f"unknown program language {language!r}: use one of "
                         f"{', '.join(LANGUAGES)}") from None


def identifier_problem(name: str, language: str) -> str | None:
    """What makes ``name`` no identifier of ``language`` (None: it is one)."""
    rule = _rule(language)
    if not isinstance(name, str) or not name:
        return "empty"
    if len(name) > rule.max_length:
        return f"{len(name)} characters (at most {rule.max_length})"
    if not rule.pattern().fullmatch(name):
        bad = next((c for c in name if not (c.isascii() and (c.isalnum() or c == "_"))), None)
        if bad is not None:
            return f"character {bad!r} is not a letter, digit or '_'"
        return "it does not start with a letter"
    if name.upper() in rule.reserved:
        return f"{name.upper()} is a reserved word of {language.upper()}"
    if rule.own is not None and rule.own.fullmatch(name):
        return f"{name} is a name the {language.upper()} program itself declares"
    return None


def check_identifier(name: str, language: str, item: str, kind: str = "name") -> str:
    """``name`` if it is an identifier of ``language``.

    Args:
        name: the name.
        language: "rapid", "krl" or "ls".
        item: where it comes from, for the message (e.g. "--name", "out.src").
        kind: what it names (e.g. "module name").

    Raises:
        ProgramNameError: naming ``item``, the name and why.
    """
    problem = identifier_problem(name, language)
    if problem is not None:
        raise ProgramNameError(f"{item}: {name!r} is not a valid {language.upper()} {kind} "
                               f"({problem}; a {kind} is {RULES[language].text})")
    return name


def _ascii(text: str) -> str:
    return unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")


def clean_identifier(text: str, language: str, fallback: str = "Program",
                     max_length: int | None = None) -> str:
    """A valid identifier of ``language`` made from ``text`` deterministically (derived
    names: module docstring). ``max_length`` may shorten the language's limit (e.g. to leave
    room for a part suffix); ``fallback`` is used when nothing of ``text`` is left."""
    rule = _rule(language)
    limit = min(rule.max_length, max_length or rule.max_length)
    s = re.sub(r"[^A-Za-z0-9_]+", "_", _ascii(str(text)))
    s = s.strip("_") or fallback
    if not s[0].isalpha():
        s = "P_" + s
    s = s[:limit].rstrip("_")
    if identifier_problem(s, language) is not None:  # reserved or one of the program's own
        s = s[:limit - 2].rstrip("_") + "_1"
    check_identifier(s, language, "cleaned name")  # cannot fail: a guard
    return s


# characters that start a comment, end a statement or open a string in RAPID, KRL or TP
_MARKERS = str.maketrans({c: " " for c in "!;\"'`\\{}"})


def comment_text(text: object, language: str) -> str:
    """One line of printable ASCII safe inside a ``language`` comment / remark.

    Line breaks, control and format characters become spaces, letters lose their accents
    (other non-ASCII characters become '?'), the comment and statement markers of the three
    languages (``! ; " ' ` \\ { }``) become spaces, runs of spaces shrink to one; a comment
    never starts with FOLD / ENDFOLD (the KRL editor's fold markers)."""
    _rule(language)
    out = []
    for ch in unicodedata.normalize("NFKD", str(text)):
        cat = unicodedata.category(ch)
        if cat[0] in "CZ" and ch != " ":  # control, format, line/paragraph separators
            out.append(" ")
        elif cat == "Mn":  # combining accent of a decomposed letter
            continue
        elif ch.isascii():
            out.append(ch)
        else:
            out.append("?")
    s = re.sub(r" +", " ", "".join(out).translate(_MARKERS)).strip()
    if re.match(r"(?i)(END)?FOLD\b", s):  # KRL's markers; the same text in every language
        s = "- " + s
    return s
