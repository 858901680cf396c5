#!/usr/bin/env python3
"""Runs `ao_capture` on malformed variants of two of the project's glTF files (its scene
`assets/scenes/cube_on_plane.glb` and the skinned walker, given a camera) and reports every run
that ends other than with exit code 0, 1 or 2 (a panic, a signal), writes a panic's message to
stderr (one caught on a task thread, as Bevy's asset loader catches its loaders'), or outlives a
time limit. Each
variant breaks one thing: node cycles and indices out of range, zero and non-finite transforms
and cameras, points, lines and strips, indices, normals, skins, morph targets, animations,
buffers, images. Standard library only; build the example first.

    cargo build --profile dev --example ao_capture   # from the repository root
    python3 docs/fuzz_ao_capture.py all default,near-field+spheres,voxels,fields

Arguments: the variants (comma-separated names, or `all`) and the techniques. The binary is
looked for under $CARGO_TARGET_DIR (default `target`), profile `debug`; the variants are
written to a temporary folder.
"""
import copy
import json
import os
import struct
import subprocess
import sys
import tempfile
import time

BIN = os.path.join(os.environ.get('CARGO_TARGET_DIR', 'target'), 'debug', 'examples', 'ao_capture')
OUT = tempfile.mkdtemp(prefix='ao_capture_fuzz_')
def load(f):
    b=open(f,'rb').read()
    l=struct.unpack('<I',b[12:16])[0]
    j=json.loads(b[20:20+l])
    rest=b[20+l:]
    bl=struct.unpack('<I',rest[0:4])[0]
    binc=rest[8:8+bl]
    return j,binc
def save(f,j,binc):
    js=json.dumps(j).encode()
    js+=b' '*((4-len(js)%4)%4)
    binc=binc+b'\0'*((4-len(binc)%4)%4)
    total=12+8+len(js)+8+len(binc)
    out=struct.pack('<III',0x46546C67,2,total)+struct.pack('<II',len(js),0x4E4F534A)+js+struct.pack('<II',len(binc),0x004E4942)+binc
    open(f,'wb').write(out)
def with_camera(j):
    j=copy.deepcopy(j)
    if 'cameras' not in j:
        j['cameras']=[{'type':'perspective','perspective':{'yfov':0.8,'znear':0.05}}]
        j['nodes'].append({'camera':0,'translation':[0,1,4]})
        j['scenes'][0]['nodes'].append(len(j['nodes'])-1)
    return j
muts={}
def primitives(j):
    return (p for me in j['meshes'] for p in me['primitives'])
def m(name):
    def d(f): muts[name]=f; return f
    return d
@m('node_cycle')
def _(j,b):
    n=j['nodes']; p=j['scenes'][0]['nodes'][0]
    n[p].setdefault('children',[]).append(p); return j,b
@m('child_out_of_range')
def _(j,b): j['nodes'][0].setdefault('children',[]).append(999); return j,b
@m('scene_node_out_of_range')
def _(j,b): j['scenes'][0]['nodes'].append(999); return j,b
@m('nan_matrix')
def _(j,b):
    for n in j['nodes']:
        n.pop('translation',None);n.pop('rotation',None);n.pop('scale',None)
        n['matrix']=[1e38]*16
        break
    return j,b
@m('huge_scale')
def _(j,b):
    for n in j['nodes']:
        if 'mesh' in n: n['scale']=[1e30,1e30,1e30]
    return j,b
@m('zero_scale_all')
def _(j,b):
    for n in j['nodes']: n['scale']=[0,0,0]
    return j,b
@m('camera_zero_yfov')
def _(j,b): j['cameras'][0]['perspective']['yfov']=0.0; return j,b
@m('camera_neg_znear')
def _(j,b): j['cameras'][0]['perspective']['znear']=-1.0; return j,b
@m('camera_zfar_lt_znear')
def _(j,b): j['cameras'][0]['perspective']['zfar']=0.01; j['cameras'][0]['perspective']['znear']=1.0; return j,b
@m('ortho_zero_mag')
def _(j,b): j['cameras'][0]={'type':'orthographic','orthographic':{'xmag':0,'ymag':0,'znear':0.1,'zfar':100}}; return j,b
@m('ortho_ok')
def _(j,b): j['cameras'][0]={'type':'orthographic','orthographic':{'xmag':4,'ymag':3,'znear':0.1,'zfar':100}}; return j,b
@m('prim_points')
def _(j,b):
    for p in primitives(j): p['mode']=0
    return j,b
@m('prim_lines')
def _(j,b):
    for p in primitives(j): p['mode']=1
    return j,b
@m('prim_strip')
def _(j,b):
    for p in primitives(j): p['mode']=5
    return j,b
@m('indices_as_vec3')
def _(j,b):
    for p in primitives(j):
        if 'indices' in p: j['accessors'][p['indices']]['type']='VEC3'
    return j,b
@m('indices_float')
def _(j,b):
    for p in primitives(j):
        if 'indices' in p: j['accessors'][p['indices']]['componentType']=5126
    return j,b
@m('indices_count_huge')
def _(j,b):
    for p in primitives(j):
        if 'indices' in p: j['accessors'][p['indices']]['count']=10**9
    return j,b
@m('no_indices_count_not_mult3')
def _(j,b):
    for p in primitives(j): p.pop('indices',None)
    return j,b
@m('normal_vec2')
def _(j,b):
    for p in primitives(j):
        if 'NORMAL' in p['attributes']: j['accessors'][p['attributes']['NORMAL']]['type']='VEC2'
    return j,b
@m('normal_count_short')
def _(j,b):
    for p in primitives(j):
        if 'NORMAL' in p['attributes']: j['accessors'][p['attributes']['NORMAL']]['count']=1
    return j,b
@m('uv_wrong')
def _(j,b):
    for p in primitives(j): p['attributes']['TEXCOORD_0']=p['attributes']['POSITION']
    return j,b
@m('material_out_of_range')
def _(j,b):
    for p in primitives(j): p['material']=99
    return j,b
@m('mesh_out_of_range')
def _(j,b):
    for n in j['nodes']:
        if 'mesh' in n: n['mesh']=99
    return j,b
@m('empty_meshes_prims')
def _(j,b):
    for me in j['meshes']: me['primitives']=[]
    return j,b
@m('buffer_truncated')
def _(j,b): return j,b[:len(b)//3]
@m('buffer_bytelength_lie')
def _(j,b): j['buffers'][0]['byteLength']=len(b)*4; return j,b
@m('bufferview_offset_past')
def _(j,b):
    j['bufferViews'][0]['byteOffset']=len(b)*2; return j,b
@m('external_uri_missing')
def _(j,b): j['buffers'].append({'uri':'missing.bin','byteLength':100}); j['bufferViews'][0]['buffer']=1; return j,b
@m('image_missing')
def _(j,b):
    j['images']=[{'uri':'nope.png'}]; j['textures']=[{'source':0}]
    j['materials'][0].setdefault('pbrMetallicRoughness',{})['baseColorTexture']={'index':0}
    return j,b
@m('texture_bad_source')
def _(j,b):
    j['textures']=[{'source':5}]
    j['materials'][0].setdefault('pbrMetallicRoughness',{})['baseColorTexture']={'index':0}
    return j,b
@m('anim_sampler_bad')
def _(j,b):
    if 'animations' in j:
        for s in j['animations'][0]['samplers']: s['input']=s['output']
    return j,b
@m('anim_target_bad_node')
def _(j,b):
    if 'animations' in j:
        for c in j['animations'][0]['channels']: c['target']['node']=999
    return j,b
@m('anim_interp_cubic_wrong')
def _(j,b):
    if 'animations' in j:
        for s in j['animations'][0]['samplers']: s['interpolation']='CUBICSPLINE'
    return j,b
@m('anim_weights_no_morph')
def _(j,b):
    if 'animations' in j:
        for c in j['animations'][0]['channels']: c['target']['path']='weights'
    return j,b
@m('skin_joint_bad')
def _(j,b):
    if 'skins' in j:
        j['skins'][0]['joints'][0]=999
    return j,b
@m('skin_ibm_short')
def _(j,b):
    if 'skins' in j and 'inverseBindMatrices' in j['skins'][0]:
        j['accessors'][j['skins'][0]['inverseBindMatrices']]['count']=1
    return j,b
@m('skin_no_ibm')
def _(j,b):
    if 'skins' in j: j['skins'][0].pop('inverseBindMatrices',None)
    return j,b
@m('skin_joints_empty')
def _(j,b):
    if 'skins' in j: j['skins'][0]['joints']=[]
    return j,b
@m('skin_on_unskinned_mesh')
def _(j,b):
    j.setdefault('skins',[{'joints':[0]}])
    for n in j['nodes']:
        if 'mesh' in n: n['skin']=0
    return j,b
@m('joints_index_past_skin')
def _(j,b):
    if 'skins' in j: j['skins'][0]['joints']=j['skins'][0]['joints'][:1]
    return j,b
@m('morph_targets_bad')
def _(j,b):
    for me in j['meshes']:
        for p in me['primitives']: p['targets']=[{'POSITION':0}]
        me['weights']=[0.5,0.5,0.5]
    return j,b
@m('sparse_accessor')
def _(j,b):
    a=j['accessors'][j['meshes'][0]['primitives'][0]['attributes']['POSITION']]
    a['sparse']={'count':1,'indices':{'bufferView':0,'componentType':5125},'values':{'bufferView':0}}
    return j,b
@m('no_scenes')
def _(j,b): j.pop('scenes'); j.pop('scene',None); return j,b
@m('scene_index_bad')
def _(j,b): j['scene']=7; return j,b
@m('extension_required')
def _(j,b): j['extensionsRequired']=['KHR_draco_mesh_compression']; j['extensionsUsed']=['KHR_draco_mesh_compression']; return j,b
@m('asset_version_3')
def _(j,b): j['asset']['version']='3.0'; return j,b
@m('two_cameras_same_node_quat_zero')
def _(j,b):
    for n in j['nodes']:
        if 'camera' in n: n['rotation']=[0,0,0,0]
    return j,b
@m('quat_nan_all')
def _(j,b):
    for n in j['nodes']: n['rotation']=[0,0,0,0]; n.pop('matrix',None)
    return j,b
@m('node_mesh_and_camera_parent_scaled0')
def _(j,b):
    j['nodes'].append({'scale':[0,1,1],'children':list(j['scenes'][0]['nodes'])})
    j['scenes'][0]['nodes']=[len(j['nodes'])-1]; return j,b
@m('positions_nan')
def _(j,b):
    a=j['accessors'][j['meshes'][0]['primitives'][0]['attributes']['POSITION']]
    v=j['bufferViews'][a['bufferView']]; off=v.get('byteOffset',0)+a.get('byteOffset',0)
    bb=bytearray(b); 
    for i in range(min(a['count']*3,300)): bb[off+4*i:off+4*i+4]=struct.pack('<f',float('nan'))
    return j,bytes(bb)
@m('positions_huge')
def _(j,b):
    a=j['accessors'][j['meshes'][0]['primitives'][0]['attributes']['POSITION']]
    v=j['bufferViews'][a['bufferView']]; off=v.get('byteOffset',0)+a.get('byteOffset',0)
    bb=bytearray(b)
    for i in range(a['count']*3): bb[off+4*i:off+4*i+4]=struct.pack('<f',3e38 if i%2 else -3e38)
    return j,bytes(bb)
@m('indices_out_of_range_values')
def _(j,b):
    p=j['meshes'][0]['primitives'][0]
    a=j['accessors'][p['indices']]; v=j['bufferViews'][a['bufferView']]; off=v.get('byteOffset',0)+a.get('byteOffset',0)
    size={5121:1,5123:2,5125:4}[a['componentType']]
    bb=bytearray(b)
    for i in range(a['count']): bb[off+size*i:off+size*i+size]=b'\xff'*size
    return j,bytes(bb)
@m('weights_nan')
def _(j,b):
    for p in primitives(j):
        if 'WEIGHTS_0' in p['attributes']:
                a=j['accessors'][p['attributes']['WEIGHTS_0']]; v=j['bufferViews'][a['bufferView']]; off=v.get('byteOffset',0)+a.get('byteOffset',0)
                if a['componentType']==5126:
                    bb=bytearray(b)
                    for i in range(a['count']*4): bb[off+4*i:off+4*i+4]=struct.pack('<f',float('nan'))
                    b=bytes(bb)
    return j,b
@m('joints_out_of_range_values')
def _(j,b):
    for p in primitives(j):
        if 'JOINTS_0' in p['attributes']:
                a=j['accessors'][p['attributes']['JOINTS_0']]; v=j['bufferViews'][a['bufferView']]; off=v.get('byteOffset',0)+a.get('byteOffset',0)
                size={5121:1,5123:2}[a['componentType']]
                bb=bytearray(b)
                for i in range(a['count']*4): bb[off+size*i:off+size*i+size]=b'\xfe'*size
                b=bytes(bb)
    return j,b
def run(path, tech, timeout=240):
    out=os.path.join(OUT, 'out.png')
    t=time.time()
    try:
        r=subprocess.run([BIN,'--scene',path,'--width','64','--height','48','--radius','0.75','--technique',tech,'--frames','6','--time','0.5','--out-ao',out],capture_output=True,timeout=timeout,env=dict(os.environ,RUST_LOG='error'))
        code=r.returncode; err=r.stderr.decode(errors='replace')
    except subprocess.TimeoutExpired:
        code='TIMEOUT'; err=''
    return code, time.time()-t, err
if __name__=='__main__':
    bases={'cube':'assets/scenes/cube_on_plane.glb','walker':'assets/characters/walker.glb'}
    techs=sys.argv[2].split(',') if len(sys.argv)>2 else ['default']
    names=sys.argv[1].split(',') if len(sys.argv)>1 and sys.argv[1]!='all' else list(muts)
    for base,f in bases.items():
        j0,b0=load(f); j0=with_camera(j0)
        for name in names:
            j,b=copy.deepcopy(j0),b0
            j,b=muts[name](j,b)
            p=os.path.join(OUT, f'{base}_{name}.glb'); save(p,j,b)
            for tech in techs:
                code,dt,err=run(p,tech)
                # A panic the app caught (Bevy's loader runs on a task thread) still puts its
                # message and backtrace on stderr: a fault too.
                bad = code not in (0,1,2) or 'panicked' in err
                lines=[l for l in err.splitlines() if 'panick' in l or 'ao_capture:' in l or 'ERROR' in l][:2]
                print(f"{'BAD ' if bad else ''}{base} {name} {tech}: exit {code} {dt:.0f}s {' | '.join(lines)[:300]}",flush=True)
