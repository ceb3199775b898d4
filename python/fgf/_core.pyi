"""Type stubs for the private native module ``fgf._core``.

Each area owns one section below; edit only your own section.
"""

__version__: str

class FgfError(ValueError): ...
class ParameterError(FgfError): ...
class SceneError(FgfError): ...

# --- transmittance (issue 2) ---
# --- field (issue 3) ---
# --- render (issue 4/5) ---
