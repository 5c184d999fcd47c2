"""The release has one source, CMakeLists.txt's project() version: the package and the C++ header say it."""
import os
import re

import mrattle

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def project_version():
    with open(os.path.join(ROOT, 'CMakeLists.txt')) as stream:
        return re.search(r'^project\(\s*MRattlePlugin\s+VERSION\s+([0-9.]+)', stream.read(), re.M).group(1)


def test_package_version_is_the_cmake_project_version():
    assert mrattle.__version__ == project_version()


def test_the_changelog_names_this_version():
    with open(os.path.join(ROOT, 'CHANGELOG.md')) as stream:
        assert '## [%s] - ' % project_version() in stream.read()


def test_cpp_header_in_the_build_tree_says_the_same():
    # The build tree's package is <build>/python/mrattle; an installed package has no build tree beside it.
    build = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(mrattle.__file__))))
    header = os.path.join(build, 'generated', 'include', 'MRattleVersion.h')
    if not os.path.exists(header):
        import pytest
        pytest.skip('no build tree beside the package: %s' % header)
    with open(header) as stream:
        text = stream.read()
    assert '#define MRATTLE_VERSION "%s"' % project_version() in text
    major, minor, patch = project_version().split('.')
    assert '#define MRATTLE_VERSION_MINOR %s' % minor in text
