# Type stub: at run time `toolkit.backlash` is `toolkit.papers.backlash` itself (toolkit/__init__.py
# registers the short name); this stub gives type checkers the same names.
from .papers.backlash import *
