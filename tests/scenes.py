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


def friction_header(mu, restitution):
    """The [scene] (0.1 s under gravity, with rotation and friction), [output] and one
    steel–steel [[contacts]] table; μ and e as TOML text (numbers or format fields)."""
    return ("[scene]\nname = \"friction\"\nduration = 0.1\ngravity = [0.0, 0.0, -9.81]\n"
            "effects = [\"gravity\", \"rotation\", \"friction\"]\n"
            "[output]\nframe_interval = 0.1\n"
            f"[[contacts]]\nbetween = [\"steel\", \"steel\"]\nsliding_friction = {mu}\n"
            f"restitution = {restitution}\n")


FLOOR = plane(("0.0", "0.0", "0.0"), ("0.0", "0.0", "1.0"))


def num(x: float) -> str:
    """A float as TOML text that reads back bit for bit."""
    return repr(float(x))
