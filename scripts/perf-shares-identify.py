#!/usr/bin/env python3
"""Shares of an `aeroform identify` profile by stage (docs/DECISIONS.md, issue 43's identify
row, round 33): `perf report --no-children --sort sym` of PERF_DATA, each symbol put in the
first group one of whose patterns it contains.

    perf record -F 2000 -g -o PERF_DATA aeroform --quiet identify SET --out DIR
    python3 scripts/perf-shares-identify.py PERF_DATA
"""
import sys,re,subprocess
data=sys.argv[1]
out=subprocess.run(['perf','report','-i',data,'--no-children','--stdio','--sort','sym'],capture_output=True,text=True).stdout
cats={'QR (householder)':['householder_qr'],
'harmonic basis + projection':['basis_rows','gemm','pulp::','cholesky_solve','solve_many','solve_columns'],
'factor passes (norms, scaled copy)':['from_row_blocks','from_columns','factorise'],
'library evaluation / Θ copy':['evaluate_rows','prepare_case'],
'CSV parsing + reading':['dec2flt','FromStr','csv_fields','read_case_csv','memchr','HashingReader','trim_matches','read_until','next_line','read_buf','from_utf8','_copy_to_iter','filemap','LineFields','copy_user'],
'preprocessing and dataset checks':['preprocess::','realfft','rustfft','sincos','__sin','__cos','record_from_table','check_sampling'],
'allocation, page faults, zeroing':['memset','page_fault','do_anonymous_page','clear_page','madvise','_int_free','_int_malloc','malloc','unmap_page','handle_mm_fault','__list_del','_raw_spin_unlock','free_pages','cfree'],
}
tot={k:0.0 for k in cats}; other=0.0; allp=0.0
for l in out.splitlines():
    m=re.match(r'\s+([0-9.]+)%\s+\[[.k]\]\s+(.*)',l)
    if not m: continue
    p=float(m.group(1)); sym=m.group(2); allp+=p
    for k,pats in cats.items():
        if any(x in sym for x in pats): tot[k]+=p; break
    else: other+=p
for k,v in tot.items(): print(f'{v:5.1f}%  {k}')
print(f'{other:5.1f}%  other (group stage, JSON, rayon, …)')
