"""Package layout: the rooms of the design card sit at the top of the repository and install as
``handeye.<room>`` (``calibration/`` -> ``handeye.calibration``); ``top/`` is the package ``handeye``
itself (its version and ``py.typed``, the PEP 561 marker covering every room). Sub-packages are
found automatically, so adding a module or a sub-package needs no change here."""

from setuptools import find_packages, setup

ROOMS = ("calibration", "drivers", "station", "rapid", "mocks")
DATA = [f"**/*.{ext}" for ext in ("yaml", "yml", "json", "md", "txt", "mod", "modx", "sys", "tmpl", "j2", "png", "html")]

packages, package_dir = ["handeye"], {"handeye": "top"}
for room in ROOMS:
    for sub in [""] + find_packages(room):
        name = f"handeye.{room}" + (f".{sub}" if sub else "")
        packages.append(name)
        package_dir[name] = room + ("/" + sub.replace(".", "/") if sub else "")

package_data = {name: DATA for name in packages}
package_data["handeye"] = ["py.typed"]
setup(packages=packages, package_dir=package_dir, package_data=package_data)
