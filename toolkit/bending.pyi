# Type stub: at run time `toolkit.bending` is `toolkit.papers.bending` itself (toolkit/__init__.py
# registers the short name); this stub gives type checkers the same names.
from .papers.bending import *
