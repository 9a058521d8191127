#!/usr/bin/perl
# test/las_write.pl: small LAS files for test/cli_las.sh, good and broken,
# written from the ASPRS LAS 1.4 R15 specification with Perl's pack, apart
# from ./tdc's reader (src/cli/las.c): the two share no code.
#
#   perl test/las_write.pl OUT MINOR FORMAT [KEY=VALUE ...] < POINTS
#
# POINTS: lines "X Y Z C", the record's integers: X, Y, Z as stored (int32)
# and C the byte at the classification's place (byte 15 for formats 0 to 5,
# where the top 3 bits are flags; byte 16 for 6 to 10).  The coordinate is
# X * scale + offset.  Every other byte of a record is filled so that a
# reader looking at the wrong place sees something else: the flags byte of
# formats 6 to 10 (byte 15) is 0xFF, the scan angle of formats 0 to 5
# (byte 16) is -5, the rest of the record and the extra bytes are 0xEE.
#
# KEY=VALUE:
#   scale=SX,SY,SZ   (default 0.01,0.01,0.01)  offset=OX,OY,OZ (default 0,0,0)
#   extra=N          N extra bytes after each record (the record length grows)
#   reclen=N         the record length field (the records are still written
#                    with the format's size plus extra)
#   wkt=S            an OGC WKT VLR (LASF_Projection 2112) holding S
#   wkt_evlr=S       the same as an EVLR after the points (1.4)
#   wktbit=1         the global encoding's WKT bit (bit 4)
#   geokeys=K:V,...  a GeoKeyDirectory VLR (LASF_Projection 34735), keys in place
#   laszip=1         LASzip's VLR ("laszip encoded", 22204)
#   fmtbyte=N        the point data format byte (128 + F: LAZ's bit; 11)
#   major=N          the major version (default 1)
#   sig=XXXX         the signature (default LASF)
#   hsize=N          the header size field
#   gap=N            N bytes between the VLRs and the points
#   count64=0        1.4: leave the 64-bit point count 0 (the legacy one holds it)
#   truncate=N       keep only the first N bytes of the file
#   cut=N            drop the last N bytes of the file
use strict;
use warnings;

my ($out, $minor, $format, @kv) = @ARGV;
die "usage: las_write.pl OUT MINOR FORMAT [KEY=VALUE ...] < POINTS\n" unless defined $format;
my %o = (scale => '0.01,0.01,0.01', offset => '0,0,0', extra => 0, major => 1, sig => 'LASF', gap => 0);
for (@kv) {
	my ($k, $v) = /^([a-z_0-9]+)=(.*)$/s or die "bad KEY=VALUE: $_\n";
	$o{$k} = $v;
}
my @scale = split /,/, $o{scale};
my @off = split /,/, $o{offset};
# the minimum record size of each format (R15 section 2.6)
my @size = (20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67);
my $reclen = $size[$format] + $o{extra};
my $hsize = $minor <= 2 ? 227 : $minor == 3 ? 235 : 375;

my @pts;
while (<STDIN>) {
	my @f = split;
	next unless @f;
	die "points: X Y Z C\n" unless @f == 4;
	push @pts, [@f];
}
my $n = @pts;

# the records
my $data = '';
my @min = (9e99) x 3;
my @max = (-9e99) x 3;
for my $p (@pts) {
	my $r = pack('l<l<l<S<', $p->[0], $p->[1], $p->[2], 0xABCD);
	if ($format < 6) {
		$r .= pack('CCcCS<', 0x49, $p->[3], -5, 0x77, 0x1234);
	} else {
		$r .= pack('CCCCs<S<', 0x11, 0xFF, $p->[3], 0x77, -500, 0x1234);
	}
	$r .= "\xEE" x ($reclen - length($r));
	$data .= $r;
	for my $c (0 .. 2) {
		my $v = $p->[$c] * $scale[$c] + $off[$c];
		$min[$c] = $v if $v < $min[$c];
		$max[$c] = $v if $v > $max[$c];
	}
}
@min = @max = (0, 0, 0) unless $n;

# the VLRs (R15 section 2.5: 54-byte header) and EVLRs (2.7: 60 bytes)
sub vlr { my ($user, $id, $d) = @_; pack('S<a16S<S<a32', 0, $user, $id, length($d), 'test/las_write.pl') . $d }
sub evlr { my ($user, $id, $d) = @_; pack('S<a16S<Q<a32', 0, $user, $id, length($d), 'test/las_write.pl') . $d }
my @vlrs;
push @vlrs, vlr('LASF_Projection', 2112, "$o{wkt}\0") if defined $o{wkt};
if (defined $o{geokeys}) {
	my @keys = map { [split /:/] } split /,/, $o{geokeys};
	push @vlrs, vlr('LASF_Projection', 34735,
		pack('S<*', 1, 1, 0, scalar(@keys), map { ($_->[0], 0, 1, $_->[1]) } @keys));
}
push @vlrs, vlr('laszip encoded', 22204, "\0" x 34) if $o{laszip};
my $vlrbytes = join '', @vlrs;
my $evlrbytes = defined $o{wkt_evlr} ? evlr('LASF_Projection', 2112, "$o{wkt_evlr}\0") : '';

# the public header block (R15 section 2.4)
my $point_offset = $hsize + length($vlrbytes) + $o{gap};
my $legacy = ($minor < 4 || $format < 6 || (defined $o{count64} && !$o{count64})) ? $n : 0;
my $h = pack('a4S<S<a16CCa32a32S<S<S<L<L<CS<L<L<5d<3d<3d<6',
	$o{sig}, 0, ($o{wktbit} ? 16 : 0), '', $o{major}, $minor, 'tdc test', 'test/las_write.pl', 1, 2025,
	$o{hsize} // $hsize, $point_offset, scalar(@vlrs), $o{fmtbyte} // $format, $o{reclen} // $reclen,
	$legacy, $legacy, 0, 0, 0, 0, @scale, @off, $max[0], $min[0], $max[1], $min[1], $max[2], $min[2]);
$h .= pack('Q<', 0) if $minor >= 3;
if ($minor >= 4) {
	my $count64 = (defined $o{count64} && !$o{count64}) ? 0 : $n;
	$h .= pack('Q<L<Q<Q<15', $evlrbytes ? $point_offset + length($data) : 0, $evlrbytes ? 1 : 0,
		$count64, $count64, (0) x 14);
}
die "header is " . length($h) . " bytes, not $hsize\n" unless length($h) == $hsize;

my $file = $h . $vlrbytes . ("\0" x $o{gap}) . $data . $evlrbytes;
$file = substr($file, 0, $o{truncate}) if defined $o{truncate};
$file = substr($file, 0, length($file) - $o{cut}) if defined $o{cut};
open(my $fh, '>:raw', $out) or die "$out: $!\n";
print $fh $file;
close($fh) or die "$out: $!\n";
