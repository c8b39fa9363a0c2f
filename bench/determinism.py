#!/usr/bin/env python3
"""Same seed, same result, at any thread count and any number of MPI ranks: a matrix over the options.

    python3 bench/determinism.py BUILD/irrcache [--only REGEX] [--variants t1,t2,t3,np2,np3] [--keep DIR]

Each case (a scene and options of `irrcache render --integrator ic|pt` or `irrcache points`) runs once per
variant: 1, 2 and 3 threads in one process (t1, t2, t3) and 2 and 3 MPI ranks (np2: 1 thread each, np3: 2
threads each; skipped without mpirun or in a build without MPI). Every variant runs in its own folder with
the same file names, and its outputs are compared with t1's byte for byte: the image (PFM), the cache file
(--save-cache), --records-json, the AOVs (EXR: the header's irrcache:seconds left out), the points' output,
and --stats less what the docs let vary (seconds, rays_per_second, phases, threads, ranks, per_rank).
Images are tiny (48 x 36 and smaller) and rays few: this checks determinism, not quality. Prints one line
per case (`same` or what differed) and exits 1 when anything differed.

`--time` is in the matrix with a budget far above what the render needs (nothing is cut, so the result
must not vary); a budget that does cut depends on the wall clock and is outside the promise (README,
"Time budget").
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SRC = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
S = os.path.join(SRC, 'scenes')


def scenes(folder, *names):
    return [os.path.join(S, folder, n) for n in names]


CORNELL, GLASS, VARNISHED, RAD = scenes('cornell-box', 'cornell-box.json', 'cornell-box-glass.json',
                                        'cornell-box-varnished.json', 'cornell-box.rad')
GLOSSY, GLOSSY20, CONDUCTOR, GGX, FLOOR = scenes(
    'cornell-box-glossy', 'cornell-box-glossy.json', 'cornell-box-glossy-20.json',
    'cornell-box-glossy-conductor.json', 'cornell-box-glossy-ggx.json', 'cornell-box-glossy-floor.json')
BUMPS, UV = scenes('cornell-box-bumps', 'cornell-box-bumps.json', 'cornell-box-uv.json')
SKY, OVERCAST, CLEAR, DOOR, STAIR = scenes('interiors', 'sky-room.json', 'sky-room-overcast.json',
                                           'sky-room-clear.json', 'door-ajar.json', 'stair-hall.json')
SPONZA, STAIRCASE = scenes('.', 'sponza.json', 'staircase2.json')  # meshes from the shared scenes folder

SMALL = ['--width', '48', '--height', '36']
IC = ['--integrator', 'ic', '--spp', '4', '--rays', '64']
PT = ['--integrator', 'pt', '--spp', '4']


def render_cases():
    """(name, scene, options) of `irrcache render`."""
    cases = []
    for scene in (CORNELL, GLOSSY, SKY, DOOR, STAIR):
        tag = os.path.basename(scene)[:-5]
        cases.append(('ic ' + tag, scene, SMALL + IC))
        cases.append(('pt ' + tag, scene, SMALL + PT))
    cases.append(('ic sponza', SPONZA, ['--width', '32', '--height', '18'] + IC))
    cases.append(('pt sponza', SPONZA, ['--width', '32', '--height', '18'] + PT))
    base = SMALL + IC
    for strategy in ('batch', 'adaptive'):
        for gather in ('stratified', 'progressive', 'hemicube'):
            rays = ['--rays', '96'] if gather == 'hemicube' else []
            cases.append((f'ic {strategy} {gather}', CORNELL,
                          base + ['--strategy', strategy, '--gather', gather] + rays))
    cases += [
        ('ic lazy (threads only)', CORNELL, base + ['--strategy', 'lazy']),
        ('ic lazy recursive (threads only)', CORNELL, base + ['--strategy', 'lazy', '--recursive']),
        ('ic hessian round', CORNELL, base + ['--error', 'hessian']),
        ('ic hessian elliptical', CORNELL, base + ['--error', 'hessian', '--record-shape', 'elliptical']),
        ('ic hessian elliptical error weight', CORNELL,
         base + ['--error', 'hessian', '--record-shape', 'elliptical', '--weight', 'error']),
        ('ic adaptive hessian', CORNELL, base + ['--strategy', 'adaptive', '--error', 'hessian']),
        ('ic hemicube hessian', CORNELL, SMALL + ['--integrator', 'ic', '--spp', '4', '--rays', '96',
                                                 '--gather', 'hemicube', '--error', 'hessian']),
        ('ic weight tl', CORNELL, base + ['--weight', 'tl']),
        ('ic weight error', CORNELL, base + ['--weight', 'error']),
        ('ic radiance cache', GLOSSY20, base + ['--radiance-cache', 'on', '--hsh-order', '4']),
        ('ic radiance cache adaptive', GLOSSY20,
         base + ['--radiance-cache', 'on', '--hsh-order', '4', '--strategy', 'adaptive']),
        ('ic radiance cache lazy (threads only)', GLOSSY20,
         base + ['--radiance-cache', 'on', '--hsh-order', '4', '--strategy', 'lazy']),
        ('ic hit records off', CORNELL, base + ['--hit-records', 'off']),
        ('ic path-traced gather', CORNELL, base + ['--path-traced-gather']),
        ('ic record sets', CORNELL, base + ['--record-sets', '4', '--record-noise', '0.01']),
        ('ic record filter off', CORNELL, base + ['--record-filter', 'off']),
        ('ic large emitters 0.001', SKY, base + ['--large-emitters', '0.001']),
        ('ic large emitters off', SKY, base + ['--large-emitters', 'off']),
        ('ic large emitters door', DOOR, base + ['--large-emitters', '0.001']),
        ('ic adaptive sampling on', CORNELL, SMALL + ['--integrator', 'ic', '--spp', '16', '--rays', '64']),
        ('ic adaptive sampling off', CORNELL, SMALL + ['--integrator', 'ic', '--spp', '16', '--rays', '64',
                                                       '--adaptive-sampling', 'off']),
        ('pt adaptive sampling', CORNELL, SMALL + ['--integrator', 'pt', '--spp', '16',
                                                   '--adaptive-sampling', 'on']),
        ('pt adaptive sampling glossy', GLOSSY, SMALL + ['--integrator', 'pt', '--spp', '16',
                                                         '--adaptive-sampling', 'on']),
        ('ic sampler random', CORNELL, base + ['--sampler', 'random']),
        ('pt sampler random', CORNELL, SMALL + PT + ['--sampler', 'random']),
        ('ic light samples 4', SKY, base + ['--light-samples', '4']),
        ('ic no gradients gradient difference', CORNELL, base + ['--no-gradients', '--gradient-difference']),
        ('ic no clamps', CORNELL, base + ['--no-gradient-clamp', '--no-neighbor-clamp', '--no-validity-clamp']),
        ('ic final accuracy scale', CORNELL, base + ['--final-accuracy-scale', '2']),
        ('ic bounces 1', CORNELL, base + ['--bounces', '1']),
        ('ic max passes 2', CORNELL, base + ['--max-passes', '2']),
        ('ic pass growth off', CORNELL, base + ['--pass-growth', 'off', '--max-passes', '6']),
        ('ic aov', GLOSSY20, base + ['--radiance-cache', 'on', '--hsh-order', '4',
                                    '--aov', 'indirect,glossy,records,density,amap']),
        ('ic aov adaptive', CORNELL, base + ['--strategy', 'adaptive', '--aov', 'indirect,density,amap']),
        ('ic time budget (not cut)', CORNELL, base + ['--time', '1000']),
        ('ic adaptive time budget (not cut)', CORNELL, base + ['--strategy', 'adaptive', '--time', '1000']),
        ('pt time budget (not cut)', CORNELL, SMALL + PT + ['--time', '1000']),
        ('ic seed 7 odd size', CORNELL, ['--width', '37', '--height', '23', '--seed', '7'] + IC),
        ('ic load cache', CORNELL, base + ['--load-cache', '@saved.cache']),
        ('ic load cache radiance', GLOSSY20, base + ['--radiance-cache', 'on', '--hsh-order', '4',
                                                     '--load-cache', '@saved.cache']),
        ('ic load cache adaptive', CORNELL, base + ['--strategy', 'adaptive', '--load-cache', '@saved.cache']),
        ('ic overcast', OVERCAST, base),
        ('ic checkpoint', CORNELL, base + ['--checkpoint', '0.001']),
        ('pt checkpoint', CORNELL, SMALL + PT + ['--checkpoint', '0.001']),
        ('ic max seed light samples', SKY, base + ['--seed', '18446744073709551615', '--light-samples', '3']),
        ('ic spp 1', CORNELL, SMALL + ['--integrator', 'ic', '--spp', '1', '--rays', '64']),
        ('ic spp 8 adaptive sampling', SKY, SMALL + ['--integrator', 'ic', '--spp', '8', '--rays', '64']),
        ('ic tiny image', CORNELL, ['--width', '3', '--height', '2'] + IC),
        ('ic one row', CORNELL, ['--width', '40', '--height', '1'] + IC),
        ('ic one column', CORNELL, ['--width', '1', '--height', '40'] + IC),
        ('pt one column adaptive', CORNELL, ['--width', '1', '--height', '40', '--integrator', 'pt',
                                             '--spp', '16', '--adaptive-sampling', 'on']),
        ('ic accuracy 0.05 min radius 0', CORNELL, base + ['-a', '0.05', '--min-radius-px', '0']),
        ('ic accuracy 1 radius bounds', CORNELL, base + ['-a', '1', '--min-radius', '0.05', '--max-radius', '0.3',
                                                         '--max-radius-px', '10']),
        ('ic uncovered min candidates', CORNELL, base + ['--uncovered', '0.2', '--min-candidates', '3']),
        ('ic adaptive weber growth', CORNELL, base + ['--strategy', 'adaptive', '--weber', '0.005',
                                                      '--adaptive-growth', '3']),
        ('ic max depth 2', SKY, base + ['--max-depth', '2']),
        ('ic radiance order 10 rays', GLOSSY20, base + ['--radiance-cache', 'on', '--radiance-rays', '128',
                                                        '--radiance-max-exponent', '100']),
        ('ic radiance hessian elliptical', GLOSSY20, base + ['--radiance-cache', 'on', '--hsh-order', '3',
                                                             '--error', 'hessian', '--record-shape', 'elliptical']),
        ('ic record sets adaptive', SKY, base + ['--strategy', 'adaptive', '--record-sets', '3']),
        ('ic hemicube record sets', CORNELL, SMALL + ['--integrator', 'ic', '--spp', '4', '--rays', '96',
                                                     '--gather', 'hemicube', '--record-sets', '3']),
        ('ic half exr aov', CORNELL, base + ['--half', '--aov', 'indirect,density']),
        ('ic bumps', BUMPS, base),
        ('pt bumps uv', UV, SMALL + PT),
        ('ic glass', GLASS, base),
        ('pt glass', GLASS, SMALL + PT),
        ('ic varnished', VARNISHED, base + ['--radiance-cache', 'on', '--hsh-order', '4']),
        ('ic conductor', CONDUCTOR, base),
        ('ic ggx radiance', GGX, base + ['--radiance-cache', 'on', '--hsh-order', '4']),
        ('pt glossy floor', FLOOR, SMALL + PT),
        ('ic rad scene', RAD, base + ['--view', os.path.join(S, 'cornell-box', 'cornell-box.vf')]),
        ('pt rad scene', RAD, SMALL + PT),
        ('ic sponza adaptive hessian', SPONZA, ['--width', '32', '--height', '18'] + IC +
         ['--strategy', 'adaptive', '--error', 'hessian']),
        ('ic staircase', STAIRCASE, ['--width', '32', '--height', '18'] + IC),
        ('ic clear sky', CLEAR, base),
    ]
    return cases


def points_cases():
    """(name, scene, options) of `irrcache points`; a points file is written as pts.txt in each folder."""
    grid = ['--grid', '0', '0', '0', '5', '2.7', '4', '--spacing', '0.7']
    return [
        ('points ic', CORNELL, ['--points', 'pts.txt', '--rays', '128', '--light-samples', '32']),
        ('points pt', CORNELL, ['--points', 'pts.txt', '--integrator', 'pt', '--samples', '32']),
        ('points ic stdin', CORNELL, ['--points', '-', '--rays', '128', '--light-samples', '32']),
        ('points ic grid df', OVERCAST, grid + ['--rays', '128', '--light-samples', '32', '--daylight-factor',
                                                '--map', 'map.png']),
        ('points pt grid df', OVERCAST, grid + ['--integrator', 'pt', '--samples', '32', '--daylight-factor']),
        ('points ic grid clear json', CLEAR, grid + ['--rays', '128', '--light-samples', '32',
                                                     '--format', 'json']),
        ('points ic accuracy', SKY, grid + ['--rays', '128', '--light-samples', '16', '-a', '0.3']),
        ('points ic one point', CORNELL, ['--points', 'one.txt', '--rays', '128', '--light-samples', '16']),
        ('points pt one point', CORNELL, ['--points', 'one.txt', '--integrator', 'pt', '--samples', '16']),
        ('points ic sponza', SPONZA, ['--grid', '-10', '0', '-5', '10', '15', '5', '--spacing', '3',
                                     '--rays', '64', '--light-samples', '16']),
        ('points ic stair depth', STAIR, ['--points', 'pts.txt', '--rays', '64', '--light-samples', '16',
                                          '--max-depth', '3', '--seed', '9']),
    ]


def points_file(path):
    import random
    rng = random.Random(3)
    with open(path, 'w') as f:
        for _ in range(40):
            f.write('%.6f %.6f %.6f 0 1 0\n' % (rng.uniform(-0.9, 0.9), rng.uniform(0.05, 1.5),
                                               rng.uniform(-0.9, 0.9)))


VARIANTS = {'t1': (0, 1), 't2': (0, 2), 't3': (0, 3), 'np2': (2, 1), 'np3': (3, 2),
            't8': (0, 8), 'np5': (5, 1)}  # the last two on request (--variants)
VOLATILE = ('seconds', 'rays_per_second', 'phases', 'threads', 'ranks', 'per_rank')


def stats_counts(path):
    d = json.load(open(path))
    for k in VOLATILE:
        d.pop(k, None)
    d.get('settings', {}).pop('threads', None)
    return d


def exr_body(path):
    """An EXR less what its header says of the run: how long it took, on how many threads."""
    body = re.sub(rb'(irrcache:seconds\x00string\x00....)[0-9.]+', rb'\1', open(path, 'rb').read(), flags=re.S)
    return re.sub(rb'"threads":[0-9]+', b'', body)


def points_json(path):
    """`irrcache points --format json` less its seconds."""
    d = json.load(open(path))
    d.pop('seconds', None)
    return d


def run_variant(binary, kind, scene, opts, variant, folder, env):
    ranks, threads = VARIANTS[variant]
    os.makedirs(folder, exist_ok=True)
    cmd = [binary, kind, scene] + opts + ['--threads', str(threads), '-q']
    if kind == 'render':
        cmd += ['-o', 'out.pfm', '--stats', 'stats.json']
        if '--integrator' in opts and opts[opts.index('--integrator') + 1] == 'ic':
            cmd += ['--records-json', 'records.json']
            if '--load-cache' not in opts:
                cmd += ['--save-cache', 'out.cache']
    else:
        cmd += ['-o', 'out.txt']
        points_file(os.path.join(folder, 'pts.txt'))
        with open(os.path.join(folder, 'one.txt'), 'w') as f:
            f.write('0.1 0.5 0.2 0 1 0\n')
    if ranks:
        cmd = ['mpirun', '--oversubscribe', '-np', str(ranks)] + cmd
    stdin = open(os.path.join(folder, 'pts.txt')) if '-' in opts else subprocess.DEVNULL
    r = subprocess.run(cmd, cwd=folder, env=env, stdin=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    if r.returncode != 0:
        return 'exit %d: %s' % (r.returncode, r.stderr.decode(errors='replace').strip().splitlines()[-1:])
    return None


def compare(ref, other):
    """What differs between two variants' folders (a list of words)."""
    diffs = []
    for name in sorted(os.listdir(ref)):
        a, b = os.path.join(ref, name), os.path.join(other, name)
        if not os.path.exists(b):
            diffs.append(name + ' missing')
        elif name == 'stats.json':
            sa, sb = stats_counts(a), stats_counts(b)
            keys = sorted(k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k))
            if keys:
                diffs.append('stats ' + ','.join('%s(%s vs %s)' % (k, json.dumps(sa.get(k))[:60],
                                                                   json.dumps(sb.get(k))[:60]) for k in keys))
        elif name == 'out.txt' and open(a, 'rb').read(1) == b'{':
            if points_json(a) != points_json(b):
                diffs.append(name)
        elif name.endswith('.exr'):
            if exr_body(a) != exr_body(b):
                diffs.append(name)
        elif open(a, 'rb').read() != open(b, 'rb').read():
            diffs.append(name)
    return diffs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('binary')
    ap.add_argument('--only', default='', help='run the cases whose name matches this regular expression')
    ap.add_argument('--variants', default='t1,t2,t3,np2,np3')
    ap.add_argument('--keep', help='keep the outputs in this folder')
    args = ap.parse_args()
    binary = os.path.abspath(args.binary)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1',
               OMPI_MCA_rmaps_base_oversubscribe='1')
    env.setdefault('IRRCACHE_SCENES', os.path.join(os.path.dirname(SRC), 'shared', 'scenes'))
    has_mpi = shutil.which('mpirun') is not None and b'libmpi' in subprocess.run(
        ['ldd', binary], stdout=subprocess.PIPE, stderr=subprocess.STDOUT).stdout
    variants = [v for v in args.variants.split(',') if v]
    root = args.keep or tempfile.mkdtemp(prefix='irrcache-determinism.')
    failed = ran = 0
    cases = [('render',) + c for c in render_cases()] + [('points',) + c for c in points_cases()]
    for kind, name, scene, opts in cases:
        if not re.search(args.only, name):
            continue
        if not os.path.exists(scene) or (scene in (SPONZA, STAIRCASE) and not os.path.isdir(env['IRRCACHE_SCENES'])):
            print('%-44s skipped (no scene)' % name, flush=True)
            continue
        folder = os.path.join(root, re.sub(r'[^A-Za-z0-9]+', '-', name))
        shutil.rmtree(folder, ignore_errors=True)
        if '@saved.cache' in opts:  # the cache the same options save, made once on 2 threads, then loaded
            saved = os.path.join(folder, 'saved.cache')
            os.makedirs(folder)
            i = opts.index('@saved.cache')
            subprocess.run([binary, kind, scene] + opts[:i - 1] + opts[i + 1:] +
                           ['--threads', '2', '-q', '-o', 'saved.pfm', '--save-cache', saved],
                           cwd=folder, env=env, check=True)
            opts = opts[:i] + [saved] + opts[i + 1:]
        results = []
        for v in variants:
            if VARIANTS[v][0] and (not has_mpi or 'threads only' in name):
                continue
            err = run_variant(binary, kind, scene, opts, v, os.path.join(folder, v), env)
            if err:
                results.append('%s: %s' % (v, err))
            elif v != variants[0]:
                d = compare(os.path.join(folder, variants[0]), os.path.join(folder, v))
                if d:
                    results.append('%s: %s' % (v, '; '.join(d)))
        failed += bool(results)
        ran += 1
        print('%-44s %s' % (name, 'same' if not results else ' | '.join(results)), flush=True)
        if not args.keep:
            shutil.rmtree(folder, ignore_errors=True)
    if not args.keep:
        shutil.rmtree(root, ignore_errors=True)
    print('%d case(s) differed' % failed)
    if not ran:
        print('no case ran: --only %r matched none whose scene is here' % args.only)
    return 1 if failed or not ran else 0


if __name__ == '__main__':
    sys.exit(main())
