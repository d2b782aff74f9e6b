"""The subset of RON (Rusty Object Notation) values that billow headers use, parsed
without any library: the value parser of `read_billow.py` (see its docstring for what
is accepted), kept apart so the reader itself stays readable. Written from
formats/SPEC.md §6 alone, like the reader.
"""


class RonError(Exception):
    pass


class RStruct:
    def __init__(self, name, fields, dups):
        self.name, self.fields, self.dups = name, fields, dups


class RTuple:
    def __init__(self, name, items):
        self.name, self.items = name, items


class RIdent:
    def __init__(self, name):
        self.name = name


class RList:
    def __init__(self, items):
        self.items = items


class RMap:
    def __init__(self, pairs):
        self.pairs = pairs


class RStr:
    def __init__(self, s):
        self.s = s


class RInt:
    def __init__(self, v):
        self.v = v


class RFloat:
    def __init__(self, v):
        self.v = v


class RBool:
    def __init__(self, v):
        self.v = v


class RChar:
    def __init__(self, c):
        self.c = c


class RonParser:
    MAX_DEPTH = 128

    def __init__(self, text):
        self.s = text
        self.i = 0
        self.depth = 0
        self.extensions = set()

    def err(self, msg):
        line = self.s.count("\n", 0, self.i) + 1
        col = self.i - (self.s.rfind("\n", 0, self.i) + 1) + 1
        raise RonError("%s at line %d column %d" % (msg, line, col))

    def ws(self):
        s, n = self.s, len(self.s)
        while self.i < n:
            c = s[self.i]
            if c in " \t\r\n":
                self.i += 1
            elif s.startswith("//", self.i):
                j = s.find("\n", self.i)
                self.i = n if j < 0 else j + 1
            elif s.startswith("/*", self.i):
                depth, self.i = 1, self.i + 2
                while depth:
                    if self.i >= n:
                        self.err("unterminated block comment")
                    if s.startswith("/*", self.i):
                        depth, self.i = depth + 1, self.i + 2
                    elif s.startswith("*/", self.i):
                        depth, self.i = depth - 1, self.i + 2
                    else:
                        self.i += 1
            else:
                break

    def peek(self):
        self.ws()
        return self.s[self.i] if self.i < len(self.s) else ""

    def expect(self, ch):
        if self.peek() != ch:
            self.err("expected %r" % ch)
        self.i += 1

    def parse_document(self):
        # optional inner attributes: #![enable(implicit_some, ...)]
        while self.peek() == "#":
            if not self.s.startswith("#!", self.i):
                self.err("unexpected '#'")
            self.i += 2
            self.expect("[")
            name = self.ident()
            if name != "enable":
                self.err("unknown attribute %r" % name)
            self.expect("(")
            while self.peek() != ")":
                self.extensions.add(self.ident())
                if self.peek() == ",":
                    self.i += 1
            self.expect(")")
            self.expect("]")
        v = self.value()
        if self.peek() != "":
            self.err("trailing characters after the header value")
        return v

    def ident(self):
        self.ws()
        s, j = self.s, self.i
        if s.startswith("r#", j) and j + 2 < len(s) and (s[j + 2].isalpha() or s[j + 2] == "_"):
            j += 2
        start = j
        if j >= len(s) or not (s[j].isalpha() or s[j] == "_"):
            self.err("expected identifier")
        while j < len(s) and (s[j].isalnum() or s[j] == "_"):
            j += 1
        self.i = j
        return s[start:j]

    def is_ident_start(self):
        c = self.peek()
        return c.isalpha() or c == "_"

    def value(self):
        self.depth += 1
        if self.depth > self.MAX_DEPTH:
            self.err("nesting too deep")
        try:
            return self._value()
        finally:
            self.depth -= 1

    def _value(self):
        c = self.peek()
        s = self.s
        if c == "":
            self.err("unexpected end of header text")
        if c == "(":
            return self.paren(None)
        if c == "[":
            self.i += 1
            items = []
            while self.peek() != "]":
                items.append(self.value())
                if self.peek() == ",":
                    self.i += 1
                elif self.peek() != "]":
                    self.err("expected ',' or ']'")
            self.i += 1
            return RList(items)
        if c == "{":
            self.i += 1
            pairs = []
            while self.peek() != "}":
                k = self.value()
                self.expect(":")
                v = self.value()
                pairs.append((k, v))
                if self.peek() == ",":
                    self.i += 1
                elif self.peek() != "}":
                    self.err("expected ',' or '}'")
            self.i += 1
            return RMap(pairs)
        if c == '"':
            return RStr(self.string())
        if c == "r" and (s.startswith('r"', self.i) or s.startswith("r#\"", self.i)
                         or (s.startswith("r#", self.i) and s[self.i + 2:self.i + 3] == "#")):
            return RStr(self.raw_string())
        if c == "b" and s.startswith('b"', self.i):
            self.i += 1
            return RStr(self.string())
        if c == "'":
            return RChar(self.char())
        if c in "+-.0123456789":
            return self.number()
        if self.is_ident_start():
            name = self.ident()
            if name in ("inf", "NaN"):
                return RFloat(float("inf") if name == "inf" else float("nan"))
            if name == "true":
                return RBool(True)
            if name == "false":
                return RBool(False)
            if self.peek() == "(":
                return self.paren(name)
            if self.peek() == "{":  # not RON, but be explicit
                self.err("unexpected '{' after identifier")
            return RIdent(name)
        self.err("unexpected character %r" % c)

    def paren(self, name):
        self.expect("(")
        # struct if the first thing is `ident :` (not `::`)
        save = self.i
        is_struct = False
        if self.is_ident_start():
            try:
                self.ident()
                if self.peek() == ":" and not self.s.startswith("::", self.i):
                    is_struct = True
            except RonError:
                pass
        self.i = save
        if is_struct:
            fields, dups = {}, []
            while self.peek() != ")":
                key = self.ident()
                self.expect(":")
                v = self.value()
                if key in fields:
                    dups.append(key)
                fields[key] = v
                if self.peek() == ",":
                    self.i += 1
                elif self.peek() != ")":
                    self.err("expected ',' or ')'")
            self.i += 1
            return RStruct(name, fields, dups)
        items = []
        while self.peek() != ")":
            items.append(self.value())
            if self.peek() == ",":
                self.i += 1
            elif self.peek() != ")":
                self.err("expected ',' or ')'")
        self.i += 1
        return RTuple(name, items)

    def string(self):
        s, n = self.s, len(self.s)
        self.i += 1  # opening quote
        out = []
        while True:
            if self.i >= n:
                self.err("unterminated string")
            c = s[self.i]
            if c == '"':
                self.i += 1
                return "".join(out)
            if c == "\\":
                out.append(self.escape())
            else:
                out.append(c)
                self.i += 1

    def escape(self):
        s = self.s
        self.i += 1
        if self.i >= len(s):
            self.err("unterminated escape")
        c = s[self.i]
        self.i += 1
        simple = {'"': '"', "\\": "\\", "/": "/", "'": "'", "n": "\n", "r": "\r",
                  "t": "\t", "0": "\0", "b": "\b", "f": "\f"}
        if c in simple:
            return simple[c]
        if c == "x":
            h = s[self.i:self.i + 2]
            if len(h) != 2 or any(ch not in "0123456789abcdefABCDEF" for ch in h):
                self.err("bad \\x escape")
            self.i += 2
            return chr(int(h, 16))
        if c == "u":
            if s.startswith("{", self.i):
                j = s.find("}", self.i)
                h = s[self.i + 1:j] if j > 0 else ""
                h2 = h.replace("_", "")
                if j < 0 or not 1 <= len(h2) <= 6 or any(ch not in "0123456789abcdefABCDEF" for ch in h2):
                    self.err("bad \\u{...} escape")
                cp = int(h2, 16)
                self.i = j + 1
            else:
                h = s[self.i:self.i + 4]
                if len(h) != 4 or any(ch not in "0123456789abcdefABCDEF" for ch in h):
                    self.err("bad \\u escape")
                cp = int(h, 16)
                self.i += 4
            if cp > 0x10FFFF or 0xD800 <= cp <= 0xDFFF:
                self.err("escape is not a Unicode scalar value")
            return chr(cp)
        if c == "\n":  # Rust line continuation: skip leading whitespace
            while self.i < len(s) and s[self.i] in " \t\r\n":
                self.i += 1
            return ""
        self.err("unknown escape \\%s" % c)

    def raw_string(self):
        s = self.s
        self.i += 1  # r
        hashes = 0
        while s.startswith("#", self.i):
            hashes += 1
            self.i += 1
        if not s.startswith('"', self.i):
            self.err("bad raw string")
        self.i += 1
        end = '"' + "#" * hashes
        j = s.find(end, self.i)
        if j < 0:
            self.err("unterminated raw string")
        out = s[self.i:j]
        self.i = j + len(end)
        return out

    def char(self):
        s = self.s
        self.i += 1
        if self.i >= len(s):
            self.err("unterminated char")
        if s[self.i] == "\\":
            c = self.escape()
        else:
            c = s[self.i]
            self.i += 1
        if not s.startswith("'", self.i):
            self.err("unterminated char")
        self.i += 1
        return c

    def number(self):
        s, n = self.s, len(self.s)
        j = self.i
        sign = 1
        if s[j] in "+-":
            sign = -1 if s[j] == "-" else 1
            j += 1
            if s.startswith("inf", j):
                self.i = j + 3
                return RFloat(sign * float("inf"))
            if s.startswith("NaN", j):
                self.i = j + 3
                return RFloat(float("nan"))
        for pfx, base, digits in (("0x", 16, "0123456789abcdefABCDEF_"),
                                  ("0o", 8, "01234567_"), ("0b", 2, "01_")):
            if s.startswith(pfx, j):
                k = j + 2
                while k < n and s[k] in digits:
                    k += 1
                txt = s[j + 2:k].replace("_", "")
                if not txt:
                    self.err("bad integer literal")
                self.i = k
                return RInt(sign * int(txt, base))
        k = j
        while k < n and (s[k].isdigit() or s[k] == "_"):
            k += 1
        is_float = False
        if k < n and s[k] == "." and not (k + 1 < n and s[k + 1] == "."):
            is_float = True
            k += 1
            while k < n and (s[k].isdigit() or s[k] == "_"):
                k += 1
        if k < n and s[k] in "eE":
            m = k + 1
            if m < n and s[m] in "+-":
                m += 1
            if m < n and s[m].isdigit():
                is_float = True
                k = m
                while k < n and (s[k].isdigit() or s[k] == "_"):
                    k += 1
        txt = s[j:k].replace("_", "")
        if txt in ("", "."):
            self.err("bad number")
        # optional type suffix (newer RON): i8..u128, f32, f64
        for suf in ("u128", "i128", "u64", "i64", "u32", "i32", "u16", "i16",
                    "u8", "i8", "f32", "f64", "usize", "isize"):
            if s.startswith(suf, k):
                k += len(suf)
                if suf[0] == "f":
                    is_float = True
                break
        self.i = k
        if is_float:
            try:
                return RFloat(sign * float(txt))
            except ValueError:
                self.err("bad float literal")
        return RInt(sign * int(txt))
