# Type stub: at run time toolkit.arm5dof is toolkit.papers.arm5dof itself (a short name
# registered by toolkit/__init__.py); this stub gives type checkers the same names.
from .papers.arm5dof import *  # noqa: F403
