"""The exceptions and warnings pgt raises.

Every error carries the message the ``pgt`` command line prints for the same problem (the file,
line and field of a bad scene file; the argument of a bad array). The classes also derive from
the built-in exception that says what happened, so ``except ValueError`` and ``except OSError``
catch what they should.
"""


class Error(Exception):
    """Base class of every error pgt raises (KeyboardInterrupt aside)."""


class InputError(Error, ValueError):
    """Bad input: a malformed or inconsistent scene, image or gate file, an argument out of
    range, an array of the wrong shape or dtype, NaN or infinity."""


class FileError(Error, OSError):
    """A file that cannot be read or written; ``errno`` is set where the system gave one."""


class GpuError(Error, RuntimeError):
    """The GPU side failed: shader errors, device limits, a lost device."""


class NoAdapterError(GpuError):
    """No GPU adapter: install mesa-vulkan-drivers and libvulkan1 (lavapipe, Vulkan on the
    CPU) or a GPU driver."""


class PgtWarning(UserWarning):
    """A remark the command line prints as ``warning: ...`` (an empty scene, pixels that did
    not reach the tolerance, particles dropped by the GPU)."""
