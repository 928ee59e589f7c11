"""Function bodies in C++ source text, for the house rules (check_house_rules.py).

A heuristic reader, not a compiler: comments, preprocessor lines and string literals are
blanked, then a function is a brace block at namespace or class level whose header (the text since the previous ';',
'{' or '}') has a parameter list and ends like a function's: ')' followed by qualifiers, a
trailing return type, or a constructor's initialiser list. Blocks inside a function (lambdas,
local classes) count as its lines. Namespaces, classes, enums and initialised variables are
not functions.
"""
import re

_CONTROL = re.compile(r"^\s*(if|for|while|switch|catch|else|do|return|case)\b")
_FUNCTION_END = re.compile(r"\)\s*(const\s*|override\s*|final\s*|noexcept\s*|mutable\s*|->\s*[\w:<>,&*\s]+)*$")
_INITIALISERS = re.compile(r"\)\s*:\s*[\w:]+[({]")
_NOT_FUNCTIONS = ("namespace", "class", "struct", "enum", "union", "extern")


def blank(text):
    """`text` with comments and string and character literals emptied, newlines kept."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "#" and text[text.rfind("\n", 0, i) + 1:i].strip() == "":  # a preprocessor line
            j = i
            while True:
                j = text.find("\n", j)
                if j < 0 or text[j - 1] != "\\":
                    break
                j += 1
            j = n if j < 0 else j
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        raw = re.match(r'R"([^(\s]*)\(', text[i:i + 20]) if c == "R" and (i == 0 or not (
            text[i - 1].isalnum() or text[i - 1] == "_")) else None
        if raw:
            end = ")" + raw.group(1) + '"'
            j = text.find(end, i + len(raw.group(0)))
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
            continue
        if c in "\"'" and not (c == "'" and i > 0 and text[i - 1].isalnum()):  # 1'000 digit separators
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def _is_function(header):
    h = " ".join(header.split())
    return ("(" in h and not h.startswith(_NOT_FUNCTIONS) and "=" not in h.split("(")[0]
            and not _CONTROL.match(h) and bool(_FUNCTION_END.search(h) or _INITIALISERS.search(h)))


def functions(text):
    """[(first line, last line, header)] of every function defined in `text` (lines from 1)."""
    s = blank(text)
    depth, header_start, line = 0, 0, 1
    current = None  # (depth, first line, header) of the function being read
    found = []
    for i, c in enumerate(s):
        if c == "\n":
            line += 1
        elif c == ";":
            if current is None:
                header_start = i + 1
        elif c == "{":
            if current is None:
                header = s[header_start:i].strip()
                if _is_function(header):
                    current = (depth, line - header.count("\n"), " ".join(header.split()))
            depth += 1
            if current is None:
                header_start = i + 1
        elif c == "}":
            depth -= 1
            if current is not None and depth == current[0]:
                found.append((current[1], line, current[2]))
                current = None
            if current is None:
                header_start = i + 1
    return found
