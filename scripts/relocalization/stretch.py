# When drive B drives along drive A (ground truth of both): its stretches within 5 m of A's path,
# and the first one at least HOLD seconds long.   stretch.py A_GT B_GT [HOLD]
import sys, math
def load(p):
    out=[]
    for line in open(p):
        if line.startswith('#') or not line.strip(): continue
        f=line.split(); out.append((float(f[0]),float(f[1]),float(f[2])))
    return out
a=load(sys.argv[1]); b=load(sys.argv[2]); hold=float(sys.argv[3]) if len(sys.argv)>3 else 5.0
A=a[::20]; t0=b[0][0]
runs=[]; start=None
for (t,x,y) in b[::20]:
    d=min(math.hypot(x-ax,y-ay) for (_,ax,ay) in A)
    if d<5:
        if start is None: start=t
    else:
        if start is not None: runs.append((start-t0,t-t0)); start=None
if start is not None: runs.append((start-t0,b[-1][0]-t0))
print('stretches within 5 m of A:', ' '.join('%.1f-%.1f'%r for r in runs))
ent=[r for r in runs if r[1]-r[0]>=hold]
print('enters (first stretch >= %.0f s):'%hold, '%.1f'%ent[0][0] if ent else None)
