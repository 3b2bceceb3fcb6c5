# Type stub: at run time `toolkit.katana` is `toolkit.papers.katana` itself (toolkit/__init__.py
# registers the short name); this stub gives type checkers the same names.
from .papers.katana import *
