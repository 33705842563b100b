"""yade-batch's parameter tables read as data: the one reader of the scene scripts' table line
(engines.run.command_line, engines.run.biaxial) and of the sweep runner's jobs (engines.run.sweep).

The format is YADE's (yade.utils.TableParamReader): ``#`` starts a comment anywhere on a line;
blank lines are skipped but counted; the first other line names the columns, each later line
gives one value per column, separated by blanks. A value ``=`` repeats the line above; ``*``
leaves the script's default (the column is left out of that line). A ``description`` column
names each line; without it the name is ``column=value,...`` over the columns ending in ``!``
(the ``!`` dropped), or over all of them, with ``__line=N__`` added to a name already taken.
Columns starting with ``!`` are yade-batch's environment variables: not values of the line.

Values are Python literals, read by ``ast.literal_eval``: numbers, 'strings' (quoted),
True/False/None, tuples (``100,300``) and lists of them. YADE's readParamsFromTable instead
``eval``s every value with ``math`` in scope, so that a table is code for any script using it;
here an expression (``pi/4``, a name, a call) is refused in one line naming the table, the line
as an editor counts it and the column. Lines are numbered as YADE numbers them, so that
YADE_BATCH=TABLE:LINE (yade-batch's, or the sweep runner's) names the same line.
"""
import ast
import os
import re

BATCH = "YADE_BATCH"  # TABLE:LINE of a yade-batch job; yade-batch of a lone script sets it empty
DESCRIPTION = "description"
MAX_BYTES = 10 * 2**20  # a table's largest size [bytes]


def _literal(path, line, column, text):
    try:
        return ast.literal_eval(text)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        raise ValueError(f"{path}, line {line}, column {column!r}: {text!r} is not a literal value (a number, "
                         f"'quoted string', True/False or a list of them); tables are read as data here, "
                         f"not evaluated: write the value itself (e.g. 0.785398 for pi/4)") from None


def read_table(path):
    """{line number: {column: value, "description": name}} of the table ``path`` (module
    docstring); refuses (ValueError, one line naming the table and line) anything else."""
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such table file" + (" (a directory or special file)" if os.path.exists(path) else ""))
    if os.path.getsize(path) > MAX_BYTES:
        raise ValueError(f"{path}: a table is at most {MAX_BYTES // 2**20} MB; this one is {os.path.getsize(path)} bytes")
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: cannot read the table: {e}") from None
    rows = [(n, re.sub(r"#.*", "", line).split()) for n, line in enumerate(text.splitlines(), start=1)]
    rows = [(n, words) for n, words in rows if words]
    if not rows:
        raise ValueError(f"{path}: the table is empty (no line of column names)")
    (head_line, heads), rows = rows[0], rows[1:]
    columns = [h.removesuffix("!") if len(h) > 1 else h for h in heads]
    twice = sorted({c for c in columns if columns.count(c) > 1})
    if twice:
        raise ValueError(f"{path}, line {head_line}: column {twice[0]!r} named twice")
    named = [c for h, c in zip(heads, columns) if h.endswith("!") and len(h) > 1] or columns
    if not rows:
        raise ValueError(f"{path}: the table has column names (line {head_line}) but no line of values")
    table, texts, names = {}, None, set()
    for n, words in rows:
        if len(words) != len(columns):
            raise ValueError(f"{path}, line {n}: {len(words)} values for the {len(columns)} columns of line {head_line}")
        if texts is None and "=" in words:
            raise ValueError(f"{path}, line {n}, column {columns[words.index('=')]!r}: '=' repeats the line above, "
                             f"but this is the first line of values")
        texts = [prev if w == "=" else w for w, prev in zip(words, texts or words)]
        row = {c: _literal(path, n, c, t) for c, t in zip(columns, texts)
               if c != DESCRIPTION and not c.startswith("!") and t != "*"}
        if DESCRIPTION in columns:
            name = texts[columns.index(DESCRIPTION)]
        else:
            name = ",".join(f"{c}={t}" for c, t in zip(columns, texts) if c in named).replace("'", "").replace('"', "")
            name += f"__line={n}__" if name in names else ""
        names.add(name)
        table[n] = {**row, DESCRIPTION: name}
    return table


def batch_line():
    """(table, line number, its row) of this yade-batch job (YADE_BATCH=TABLE:LINE), or None
    outside yade-batch; refuses (ValueError) a line that is not one of the table's values."""
    batch = os.environ.get(BATCH)
    if not batch:
        return None
    path, _, line = batch.rpartition(":")
    if not path or not line.isdigit():
        raise ValueError(f"{BATCH}={batch!r}: expected TABLE:LINE (the table's file and a line number)")
    table = read_table(path)
    if int(line) not in table:
        raise ValueError(f"{BATCH}={batch}: line {line} of {path} is not a line of values "
                         f"(those are lines {', '.join(map(str, sorted(table)))})")
    return path, int(line), table[int(line)]
