$path0 << EOD
0.285674 3.58048 -
0.912123 0.843455 -
3.39615 0.210066 -
13.0692 0.055256 -
EOD
$pm0 << EOD
0.962603 0.00744282 preview
2.69464 0.00202494 final
2.24074 0.00360506 -
2.04944 0.00413154 -
5.09733 0.00159475 -
2.26301 0.00239517 -
3.82175 0.00189534 -
3.07563 0.00197988 -
2.39509 0.00221166 -
3.95427 0.00166475 -
6.3857 0.00133267 -
EOD
$pmcurve0 << EOD
0.962603 0.00744282 preview
2.04944 0.00413154 -
2.24074 0.00360506 -
2.26301 0.00239517 -
2.39509 0.00221166 -
2.69464 0.00202494 final
3.07563 0.00197988 -
3.82175 0.00189534 -
3.95427 0.00166475 -
5.09733 0.00159475 -
6.3857 0.00133267 -
EOD
$front0 << EOD
0.285674 3.58048 -
0.912123 0.843455 -
0.962603 0.00744282 preview
2.04944 0.00413154 -
2.24074 0.00360506 -
2.26301 0.00239517 -
2.39509 0.00221166 -
2.69464 0.00202494 final
3.07563 0.00197988 -
3.82175 0.00189534 -
3.95427 0.00166475 -
5.09733 0.00159475 -
6.3857 0.00133267 -
EOD
$presets0 << EOD
0.962603 0.00744282 preview
2.69464 0.00202494 final
EOD
$path1 << EOD
0.159588 0.226761 -
0.607863 0.0488014 -
2.4749 0.0107455 -
9.67699 0.00262325 -
EOD
$pm1 << EOD
0.537294 0.00573715 preview
1.32762 0.00142455 final
1.12056 0.00258295 -
1.14279 0.00164602 -
1.84061 0.00142666 -
0.994059 0.00179251 -
1.922 0.00128361 -
1.6921 0.00133909 -
1.01446 0.0017145 -
1.71876 0.000972448 -
2.44016 0.000758103 -
EOD
$pmcurve1 << EOD
0.537294 0.00573715 preview
0.994059 0.00179251 -
1.01446 0.0017145 -
1.14279 0.00164602 -
1.32762 0.00142455 final
1.6921 0.00133909 -
1.71876 0.000972448 -
2.44016 0.000758103 -
EOD
$front1 << EOD
0.159588 0.226761 -
0.537294 0.00573715 preview
0.994059 0.00179251 -
1.01446 0.0017145 -
1.14279 0.00164602 -
1.32762 0.00142455 final
1.6921 0.00133909 -
1.71876 0.000972448 -
2.44016 0.000758103 -
EOD
$presets1 << EOD
0.537294 0.00573715 preview
1.32762 0.00142455 final
EOD
$path2 << EOD
0.0963355 7.44829 -
0.269708 2.70614 -
0.971538 0.842645 -
3.69495 0.111139 -
15.0634 0.0386054 -
EOD
$pm2 << EOD
0.217998 0.0404733 preview
0.549229 0.0312217 final
0.470458 0.0315423 -
0.317764 0.0719644 -
1.58062 0.0435144 -
0.553813 0.034984 -
0.55927 0.029947 -
0.554558 0.0312217 -
0.560318 0.0312217 -
0.67878 0.0296768 -
0.951603 0.0302638 -
EOD
$pmcurve2 << EOD
0.217998 0.0404733 preview
0.470458 0.0315423 -
0.549229 0.0312217 final
0.55927 0.029947 -
0.67878 0.0296768 -
EOD
$front2 << EOD
0.0963355 7.44829 -
0.217998 0.0404733 preview
0.470458 0.0315423 -
0.549229 0.0312217 final
0.55927 0.029947 -
0.67878 0.0296768 -
EOD
$presets2 << EOD
0.217998 0.0404733 preview
0.549229 0.0312217 final
EOD
$path3 << EOD
0.363853 0.114523 -
1.16405 0.0260191 -
4.19988 0.00616203 -
16.2526 0.00151158 -
EOD
$pm3 << EOD
1.03934 0.0129435 preview
1.88221 0.00308022 final
1.674 0.0048199 -
1.97908 0.00614138 -
2.53368 0.00173294 -
1.54166 0.00328103 -
2.89614 0.00296753 -
2.46368 0.00309036 -
1.50011 0.00316512 -
2.33102 0.00233298 -
3.23156 0.00198626 -
EOD
$pmcurve3 << EOD
1.03934 0.0129435 preview
1.50011 0.00316512 -
1.88221 0.00308022 final
2.33102 0.00233298 -
2.53368 0.00173294 -
EOD
$front3 << EOD
0.363853 0.114523 -
1.03934 0.0129435 preview
1.50011 0.00316512 -
1.88221 0.00308022 final
2.33102 0.00233298 -
2.53368 0.00173294 -
16.2526 0.00151158 -
EOD
$presets3 << EOD
1.03934 0.0129435 preview
1.88221 0.00308022 final
EOD
$path4 << EOD
0.880109 3.67449 -
3.36356 0.911427 -
13.093 0.224384 -
EOD
$pm4 << EOD
2.60439 0.00781629 preview
6.66944 0.0034622 final
4.67737 0.00434976 -
4.80665 0.00552653 -
12.4863 0.00295391 -
6.13066 0.0038145 -
9.29859 0.0033035 -
8.636 0.00341013 -
6.86215 0.00349085 -
11.2103 0.00313906 -
19.4978 0.00300465 -
EOD
$pmcurve4 << EOD
2.60439 0.00781629 preview
4.67737 0.00434976 -
6.13066 0.0038145 -
6.66944 0.0034622 final
8.636 0.00341013 -
9.29859 0.0033035 -
11.2103 0.00313906 -
12.4863 0.00295391 -
EOD
$front4 << EOD
0.880109 3.67449 -
2.60439 0.00781629 preview
4.67737 0.00434976 -
6.13066 0.0038145 -
6.66944 0.0034622 final
8.636 0.00341013 -
9.29859 0.0033035 -
11.2103 0.00313906 -
12.4863 0.00295391 -
EOD
$presets4 << EOD
2.60439 0.00781629 preview
6.66944 0.0034622 final
EOD
$path5 << EOD
0.635913 0.220313 -
2.49111 0.0486853 -
10.0016 0.0106704 -
EOD
$pm5 << EOD
1.65869 0.00550751 preview
3.32221 0.0012663 final
2.61657 0.00223328 -
3.0503 0.00155161 -
3.89794 0.0012499 -
2.55125 0.00162176 -
4.77094 0.00115456 -
4.1967 0.00125668 -
3.22015 0.00125807 -
4.50664 0.000838186 -
7.13877 0.0006247 -
EOD
$pmcurve5 << EOD
1.65869 0.00550751 preview
2.55125 0.00162176 -
3.0503 0.00155161 -
3.22015 0.00125807 -
3.89794 0.0012499 -
4.50664 0.000838186 -
7.13877 0.0006247 -
EOD
$front5 << EOD
0.635913 0.220313 -
1.65869 0.00550751 preview
2.55125 0.00162176 -
3.0503 0.00155161 -
3.22015 0.00125807 -
3.89794 0.0012499 -
4.50664 0.000838186 -
7.13877 0.0006247 -
EOD
$presets5 << EOD
1.65869 0.00550751 preview
3.32221 0.0012663 final
EOD
set terminal pngcairo size 1280,1440 font ',11'
set output '/tmp/bench_full/error_vs_time.png'
set logscale xy
set format x '%g'
set format y '%g'
set xtics (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000)
set xlabel 'time (s)'
set ylabel 'relMSE'
set grid xtics ytics mxtics mytics
set key top right box opaque font ',9'
set datafile missing 'nan'
set multiplot layout 3,2 title 'error against time (medians; circled: Pareto frontier)'
set title 'cornell-box'
set xrange [0.19045:19.6038]
set yrange [0.000666335:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.106392:14.5155]
set yrange [0.000379051:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0642237:22.5951]
set yrange [0.0148384:29.7932]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.242569:24.379]
set yrange [0.000755791:0.45809]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-512'
set xrange [0.586739:29.2467]
set yrange [0.00147695:14.698]
plot $path4 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm4 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve4 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front4 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets4 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse-512'
set xrange [0.423942:15.0025]
set yrange [0.00031235:0.881251]
plot $path5 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm5 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve5 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front5 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets5 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
