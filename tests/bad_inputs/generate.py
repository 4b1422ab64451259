"""Writes the scenario files of tests/bad_inputs/ (one kind of mistake each,
NN_name.toml, with NN_name.args for extra command-line arguments), the
include helpers cycle_other.toml and chain/. The NN_name.expected files (the
exact stderr line of `capdyn check`) are NOT written here: each was read and
checked by hand against the file (location, key, expected, got) and is kept
under version control; tests/test_bad_inputs.c asserts them.
Usage: python3 tests/bad_inputs/generate.py"""
import os
D = os.path.dirname(os.path.abspath(__file__))
BALL='''[simulation]
duration = 1.0

[[system]]
name = "ball"
mass = 1.0
inertia = [0.1, 0.1, 0.1]
checkpoints = [[0, 0, -0.1, 0]]
'''
GROUND='''
[[target]]
name = "ground"
mass = 1.0
inertia = [1, 1, 1]
position = [0, 0, -1]
shape = { type = "box", size = [4, 4, 0.2] }

[[pair]]
checkpoints = "ball"
shape = "ground"
'''
ARM='''[simulation]
duration = 1.0

[[system]]
name = "arm"
base = "fixed"

[[system.link]]
name = "upper"
mass = 1.0
inertia = [0.01, 0.01, 0.01]
'''
cases = {}
def c(name, text, args=None, comment=None):
    cases[name]=(text,args,comment)

c('syntax_unclosed_header', '[simulation\nduration = 1.0\n')
c('syntax_missing_value', '[simulation]\nduration =\n')
c('syntax_duplicate_key', BALL.replace('duration = 1.0\n','duration = 1.0\nduration = 2.0\n'))
c('syntax_unterminated_string', BALL.replace('name = "ball"','name = "ball'))
c('syntax_bad_escape', BALL.replace('name = "ball"','name = "b\\qall"'))
c('type_duration_string', BALL.replace('duration = 1.0','duration = "long"'))
c('type_mass_array', BALL.replace('mass = 1.0','mass = [1.0]'))
c('type_inertia_string', BALL.replace('inertia = [0.1, 0.1, 0.1]','inertia = "diag"'))
c('nan_gravity', BALL.replace('duration = 1.0','duration = 1.0\ngravity = [0, nan, -9.81]'))
c('inf_mass', BALL.replace('mass = 1.0','mass = inf'))
c('negative_mass', BALL.replace('mass = 1.0','mass = -2.5'))
c('zero_mass', BALL.replace('mass = 1.0','mass = 0'))
c('negative_duration', BALL.replace('duration = 1.0','duration = -1.0'))
c('unknown_top_key', BALL.replace('[simulation]','[simulaton]'))
c('unknown_system_key', BALL.replace('mass = 1.0','mas = 1.0'))
c('unknown_link_key', ARM.replace('inertia = [0.01','inerta = [0.01'))
c('missing_duration', BALL.replace('duration = 1.0','output_dt = 0.01'))
c('missing_system', '[simulation]\nduration = 1.0\n')
c('missing_mass', BALL.replace('mass = 1.0\n',''))
c('bad_integrator', BALL.replace('duration = 1.0','duration = 1.0\nintegrator = "rk45"'))
c('inertia_not_positive', BALL.replace('inertia = [0.1, 0.1, 0.1]','inertia = [0.1, -0.1, 0.1]'))
c('inertia_triangle', BALL.replace('inertia = [0.1, 0.1, 0.1]','inertia = [1, 1, 3]'))
c('inertia_asymmetric', BALL.replace('inertia = [0.1, 0.1, 0.1]','inertia = [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]'))
c('include_missing', 'include = ["no_such_file.toml"]\n' + BALL)
c('include_cycle', 'include = ["cycle_other.toml"]\n' + BALL)
c('include_not_a_string', 'include = [1]\n' + BALL)
c('include_directory', 'include = "chain"\n' + BALL)
c('include_chain_too_deep', 'include = ["chain/c01.toml"]\n' + BALL)
c('override_huge_index', BALL, ['--set', 'system[99999999999999].mass=1'])
c('override_bad_value', BALL, ['--set', 'simulation.duration=[1,'])
c('override_unknown_key', BALL, ['--set', 'simulation.durration=2'])
c('override_index_out_of_range', BALL, ['--set', 'system[3].mass=2'])
c('override_include', BALL, ['--set', 'include=["x.toml"]'])
c('hull_flat', BALL + '\n[[system.shape]]\nname = "plate"\ntype = "convex"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\n')
c('hull_too_many_vertices', BALL + '\n[[system.shape]]\nname = "blob"\ntype = "convex"\nvertices = [' + ', '.join('[%d, %d, %d]' % (i % 5, (i // 5) % 5, i // 25) for i in range(130)) + ']\n')
c('rotation_zero_quaternion', BALL.replace('mass = 1.0','mass = 1.0\nquaternion = [0, 0, 0, 0]'))
c('rotation_rpy_and_quaternion', BALL.replace('mass = 1.0','mass = 1.0\nrpy_deg = [0, 0, 90]\nquaternion = [1, 0, 0, 0]'))
c('key_too_many_names', BALL + 'a' + '.a' * 39 + ' = 1\n')
c('nesting_too_deep', 'x = ' + '[' * 70 + ']' * 70 + '\n' + BALL)
c('duration_1e300', BALL.replace('duration = 1.0','duration = 1e300'))
c('output_dt_zero', BALL.replace('duration = 1.0','duration = 1.0\noutput_dt = 0'))
c('mu_above_mu_max', BALL + GROUND + 'mu_max = 0.3\nmu = 0.5\n')
c('pair_unknown_system', BALL + GROUND.replace('checkpoints = "ball"','checkpoints = "bal"'))
c('pair_unknown_shape', BALL + GROUND.replace('shape = "ground"','shape = "ground/flor"'))
c('link_unknown_parent', ARM + '\n[[system.link]]\nname = "fore"\nparent = "uper"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n')
c('duplicate_system_name', BALL + '\n[[system]]\nname = "ball"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]\n')
c('q0_outside_limit', ARM + 'limit_deg = [-90, 90]\nq0_deg = 120\n')
c('control_characters_in_name', BALL.replace('name = "ball"', 'name = "ball\\n\\u001b[31mred"'))
c('negative_checkpoint_radius', BALL.replace('checkpoints = [[0, 0, -0.1, 0]]','checkpoints = [[0, 0, -0.1, -0.01]]'))
c('actuator_table_not_increasing', ARM + 'actuator = { type = "table", table = [[0, 1], [0.5, 2], [0.5, 3]] }\n')
c('contact_rule_and_K', BALL + '\n[contact]\nK = 1e5\nrule = { k_soft = 1e4, k_ratio = 10, m_eff = 1 }\n')
c('fixed_base_velocity', ARM.replace('base = "fixed"','base = "fixed"\nvelocity = [1, 0, 0]'))
c('event_capacity_too_big', BALL.replace('duration = 1.0','duration = 1.0\nevent_capacity = 1000000000'))
c('max_steps_fraction', BALL.replace('duration = 1.0','duration = 1.0\nmax_steps = 1.5'))
c('max_rhs_evals_negative', BALL.replace('duration = 1.0','duration = 1.0\nmax_rhs_evals = -1'))
c('gripper_type_unknown', BALL + '\n[gripper]\ntype = "claw"\n')
c('shape_key_for_other_type', BALL + '\n[[system.shape]]\nname = "s"\ntype = "sphere"\nradius = 0.1\nsize = [1, 1, 1]\n')
c('vector_wrong_length', BALL.replace('mass = 1.0','mass = 1.0\nposition = [0, 0]'))
c('sampling_interpolate_with_rk4', BALL.replace('duration = 1.0','duration = 1.0\nintegrator = "rk4"\nsampling = "interpolate"'))
c('target_palm_frame_without_hand', '[simulation]\nduration = 0.1\n\n[[target]]\nname = "object"\nmass = 0.3\n'
  'inertia = [1e-4, 1e-4, 1e-4]\nframe = "palm"\nposition = [0.0, 0.07, 0.0]\nshape = { type = "sphere", radius = 0.03 }\n')

for f in os.listdir(D):
    if f[:2].isdigit() and not f.endswith('.expected'): os.remove(os.path.join(D,f))
for i,(name,(text,args,comment)) in enumerate(cases.items(),1):
    base='%02d_%s' % (i,name)
    open(os.path.join(D,base+'.toml'),'w').write(text)
    if args: open(os.path.join(D,base+'.args'),'w').write('\n'.join(args)+'\n')
open(os.path.join(D,'cycle_other.toml'),'w').write('# included by the include_cycle case; includes it back\ninclude = ["%s"]\n' % [('%02d_%s.toml'%(i,n)) for i,n in enumerate(cases,1) if n=='include_cycle'][0])
for i in range(1,41):
    open(os.path.join(D,'chain','c%02d.toml'%i),'w').write('include = ["c%02d.toml"]\n' % (i+1) if i<40 else '# the end of a chain deeper than the loader allows\n')
print(len(cases))
