import sys
p='oit-core/src/setup.rs'
s=open(p).read()
if sys.argv[1]=='add':
    s=s.replace("use crate::{Aabb, Camera, MAX_SIZE, Scene, Settings, Shading};",
    "use crate::{Aabb, Camera, MAX_SIZE, Scene, Settings, Shading};\npub static DIAG: [std::sync::atomic::AtomicU64; 4] = [const { std::sync::atomic::AtomicU64::new(0) }; 4]; //DIAG\nfn diag(i: usize, t: std::time::Instant) { DIAG[i].fetch_add(t.elapsed().as_nanos() as u64, std::sync::atomic::Ordering::Relaxed); } //DIAG",1)
    s=s.replace("            snap.vertices(&mut scratch.vertices, &mvp, &normal_matrix(&inst.transform), mesh);\n",
    "            let t0 = std::time::Instant::now(); //DIAG\n            snap.vertices(&mut scratch.vertices, &mvp, &normal_matrix(&inst.transform), mesh);\n            diag(0, t0); //DIAG\n",1)
    s=s.replace("        let chunks = &mut chunks[..n];\n","        let chunks = &mut chunks[..n];\n        let t0 = std::time::Instant::now(); //DIAG\n",1)
    s=s.replace("        copy_chunks(out, start, chunks, records, record)\n","        diag(1, t0); //DIAG\n        let t0 = std::time::Instant::now(); //DIAG\n        let r = copy_chunks(out, start, chunks, records, record); //DIAG\n        diag(2, t0); //DIAG\n        r //DIAG\n",1)
else:
    s='\n'.join(l for l in s.split('\n') if not l.endswith('//DIAG'))
    s=s.replace("        let chunks = &mut chunks[..n];\n        for_each_chunk","        let chunks = &mut chunks[..n];\n        for_each_chunk")
    s=s.replace("        });\n        let r = copy_chunks","        });\n        copy_chunks")
open(p,'w').write(s)
