import sys, statistics as st
for f in sys.argv[1:]:
    a={};b={}
    for line in open(f):
        parts=[p.strip() for p in line.split('|')]
        head=parts[0].split(); v=head[0]; r=int(head[2])
        (a if v=='A' else b)[r]=float(parts[6])
    rs=sorted(set(a)&set(b)); d=[b[r]/a[r]-1 for r in rs]
    print(f, f"CPU s median A {st.median(a.values()):.2f} B {st.median(b.values()):.2f}; B/A-1 median {100*st.median(d):+.1f}%; B lower {sum(x<0 for x in d)}/{len(d)}")
