"""Scene-text builders shared by the engine tests (steel spheres and planes; numbers as TOML
text, so a test can leave ``{format}`` fields in them)."""


def sphere(position, velocity=("0.0", "0.0", "0.0"), radius="0.001"):
    """A steel [[particles]] table; coordinates as TOML text (numbers or format fields)."""
    return (f"[[particles]]\nmaterial = \"steel\"\nradius = {radius}\n"
            f"position = [{', '.join(position)}]\nvelocity = [{', '.join(velocity)}]\n")


def plane(point, normal):
    """A steel plane [[walls]] table; coordinates as TOML text."""
    return (f"[[walls]]\nkind = \"plane\"\npoint = [{', '.join(point)}]\n"
            f"normal = [{', '.join(normal)}]\nmaterial = \"steel\"\n")


FLOOR = plane(("0.0", "0.0", "0.0"), ("0.0", "0.0", "1.0"))


def num(x: float) -> str:
    """A float as TOML text that reads back bit for bit."""
    return repr(float(x))
