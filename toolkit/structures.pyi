# Type stub: at run time `toolkit.structures` is `toolkit.papers.structures` itself (toolkit/__init__.py
# registers the short name); this stub gives type checkers the same names.
from .papers.structures import *
