# Type stub: at run time `toolkit.arm5dof` is `toolkit.papers.arm5dof` itself (toolkit/__init__.py
# registers the short name); this stub gives type checkers the same names.
from .papers.arm5dof import *
