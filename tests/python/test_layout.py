"""docs/layout.md is true: every file or folder it names in backticks exists in the source tree
(a path from the root, or a name found under the tree: `step.cc` is platforms/common/src/kernels/step.cc),
and every top-level source folder is named there."""
import glob
import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# Names of build products, not source files.
BUILT = {'MRattlePlatforms.h', 'MRattleVersion.h', 'libMRattlePluginReference.so'}
SKIP_DIRS = {'.git', 'build', '.gpu', '.pytest_cache'}  # not source: VCS, builds, tool caches


def tree():
    paths = set()
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith('build')]
        rel = os.path.relpath(folder, ROOT)
        if rel != '.':
            paths.add(rel + '/')
        paths.update(os.path.normpath(os.path.join(rel, f)) for f in files)
    return paths


def named_paths(text):
    """Backticked tokens that look like a file or folder: a '/' or a file extension, no code."""
    for token in re.findall(r'`([^`\s]+)`', text):
        if re.search(r'[()<>=,]', token) or token.startswith(('-', '$', '.')) and token != '.ci/':
            continue
        if '/' in token or re.search(r'\.(h|cpp|cc|py|sh|md|i|txt|in|cmake)$', token):
            yield token


def exists(token, paths):
    if token in BUILT or glob.glob(os.path.join(ROOT, token)):
        return True
    name = token.rstrip('/')
    # A folder, a file, or a class named by its path without the extension (`src/RigidBodySearch`).
    ending = '/$' if token.endswith('/') else r'(/|\.\w+)?$'
    pattern = re.compile('(^|/)' + re.escape(name).replace(r'\*', '[^/]*') + ending)
    return any(pattern.search(p) for p in paths)


def test_every_path_layout_md_names_exists():
    with open(os.path.join(ROOT, 'docs', 'layout.md')) as stream:
        text = stream.read()
    paths = tree()
    names = list(named_paths(text))
    assert len(names) > 30
    missing = [n for n in names if not exists(n, paths)]
    assert not missing, 'docs/layout.md names what is not in the tree: %s' % missing


def test_every_top_level_source_folder_is_named():
    with open(os.path.join(ROOT, 'docs', 'layout.md')) as stream:
        text = stream.read()
    for folder in sorted(os.listdir(ROOT)):
        if os.path.isdir(os.path.join(ROOT, folder)) and folder not in SKIP_DIRS and not folder.startswith('build') \
                and folder not in ('shared', 'output'):
            assert '`%s/`' % folder in text or '`%s' % folder in text, 'docs/layout.md does not name %s/' % folder
