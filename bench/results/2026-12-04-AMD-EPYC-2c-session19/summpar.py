import sys, statistics as st
a={};b={}
for line in open(sys.argv[1]):
    parts=[p.strip() for p in line.split('|')]
    head=parts[0].split(); v=head[0]; r=int(head[2])
    ns=float(parts[8]); (a if v=='A' else b)[r]=ns
rs=sorted(set(a)&set(b))
d=[b[r]/a[r]-1 for r in rs]
print("A", [a[r] for r in rs]); print("B", [b[r] for r in rs])
print(f"median A {st.median(a[r] for r in rs)} B {st.median(b[r] for r in rs)}; B/A-1 median {100*st.median(d):+.1f}% ; B faster {sum(x<0 for x in d)}/{len(d)}")
