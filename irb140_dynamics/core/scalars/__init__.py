"""Number types the algorithms run on besides floats and arrays: ``dual`` numbers (exact
partial derivatives) and ``interval`` numbers (rigorous enclosures).

May import: nothing of the package.
"""
