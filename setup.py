"""Package layout: ``src/handeye`` is the package; its rooms (``calibration``, ``drivers``, ``station``,
``rapid``, ``mocks``) are its sub-packages. Sub-packages and their data files are found automatically,
so adding a module or a sub-package needs no change here."""

from setuptools import find_packages, setup

DATA = [f"**/*.{ext}" for ext in ("yaml", "yml", "json", "md", "txt", "mod", "modx", "sys", "tmpl", "j2", "png", "html")]

packages = find_packages("src")
package_data = {name: DATA for name in packages}
package_data["handeye"] = ["py.typed"]
setup(packages=packages, package_dir={"": "src"}, package_data=package_data)
