import sys, statistics as st
a={};b={}
for line in open(sys.argv[1]):
    f=line.split(); v=f[0]; r=int(f[2]); t=float(f[-1]); (a if v=='A' else b)[r]=t
rs=sorted(set(a)&set(b)); d=[b[r]/a[r]-1 for r in rs]
print("A", [a[r] for r in rs]); print("B", [b[r] for r in rs])
print(f"median A {st.median(a[r] for r in rs):.2f} B {st.median(b[r] for r in rs):.2f}; B/A-1 median {100*st.median(d):+.1f}%; B faster {sum(x<0 for x in d)}/{len(d)}")
