# Scores a relocalisation pair (scripts/relocalization/pairs.sh): A_GT A_MAP_TUM B_GT B_MAP_TUM.
# A's map frame is fitted to its ground truth (rigid, Horn); B's map-frame poses are scored in it
# without a fit of their own; B "enters" A's area at the first 5 s spent within 5 m of A's path.
import sys, math, bisect
def load(p):
    out=[]
    for line in open(p):
        if line.startswith('#') or not line.strip(): continue
        f=[float(v) for v in line.split()]; out.append(f)
    return out
def interp(gt, t):
    ts=[g[0] for g in gt]
    i=bisect.bisect_left(ts,t)
    if i<=0 or i>=len(ts): return None
    a,b=gt[i-1],gt[i]; s=(t-a[0])/(b[0]-a[0])
    return [a[k]+s*(b[k]-a[k]) for k in (1,2,3)]
agt,aest,bgt,bmap=[load(p) for p in sys.argv[1:5]]
pairs=[(interp(agt,e[0]),e[1:4]) for e in aest]; pairs=[(g,e) for g,e in pairs if g]
# full SE(3) fit est(A map frame) -> gt world (Horn's quaternion method, power iteration)
n=len(pairs); gc=[sum(g[k] for g,_ in pairs)/n for k in range(3)]; ec=[sum(e[k] for _,e in pairs)/n for k in range(3)]
S=[[0.0]*3 for _ in range(3)]
for g,e in pairs:
    for a in range(3):
        for b in range(3): S[a][b]+=(e[a]-ec[a])*(g[b]-gc[b])
Sxx,Sxy,Sxz=S[0];Syx,Syy,Syz=S[1];Szx,Szy,Szz=S[2]
N=[[Sxx+Syy+Szz,Syz-Szy,Szx-Sxz,Sxy-Syx],[Syz-Szy,Sxx-Syy-Szz,Sxy+Syx,Szx+Sxz],[Szx-Sxz,Sxy+Syx,-Sxx+Syy-Szz,Syz+Szy],[Sxy-Syx,Szx+Sxz,Syz+Szy,-Sxx-Syy+Szz]]
sh=sum(abs(v) for r in N for v in r)
q=[1.0,0,0,0]
for _ in range(2000):
    q2=[sum((N[r][c]+(sh if r==c else 0))*q[c] for c in range(4)) for r in range(4)]
    m=math.sqrt(sum(v*v for v in q2)); q=[v/m for v in q2]
w,x,y,z=q
R=[[1-2*(y*y+z*z),2*(x*y-w*z),2*(x*z+w*y)],[2*(x*y+w*z),1-2*(x*x+z*z),2*(y*z-w*x)],[2*(x*z-w*y),2*(y*z+w*x),1-2*(x*x+y*y)]]
def to_world(e):
    d=[e[k]-ec[k] for k in range(3)]
    return [sum(R[r][c]*d[c] for c in range(3))+gc[r] for r in range(3)]
ate_a=math.sqrt(sum(sum((a-b)**2 for a,b in zip(to_world(e),g)) for g,e in pairs)/n)
# B: when it first came within 5 m of A's path, when it was placed, its error after
A=[(g[1],g[2]) for g in agt[::20]]
enter=None; start=None
for g in bgt[::20]:
    d=min(math.hypot(g[1]-x,g[2]-y) for x,y in A)
    if d<5:
        if start is None: start=g[0]
        if g[0]-start>=5.0: enter=start; break
    else: start=None
errs=[]
for e in bmap:
    g=interp(bgt,e[0])
    if g: errs.append(math.sqrt(sum((a-b)**2 for a,b in zip(to_world(e[1:4]),g))))
placed=bmap[0][0] if bmap else None
print('A ATE (se3 aligned) %.3f m; B enters A area at %s, placed at %s (delay %s s); B map-frame ATE %s m, max %s m over %d poses'%(
  ate_a, '%.1f'%(enter-bgt[0][0]) if enter else None, '%.1f'%(placed-bgt[0][0]) if placed else None,
  '%.1f'%(placed-enter) if placed and enter else None,
  '%.3f'%math.sqrt(sum(x*x for x in errs)/len(errs)) if errs else None, '%.3f'%max(errs) if errs else None, len(errs)))
